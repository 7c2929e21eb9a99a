// The generated worlds, loaded as the simulator loads them (writeWorld -> loadScenario ->
// loadWorldMesh -> RayCaster) and measured against their design: breakwater block sizes and
// gaps, canyon width along its length, open water at every start and goal, blocked straight
// lines where a detour is intended, and collision-free reference routes.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "auv/sim/raycast/ray_caster.h"
#include "auv/sim/sensors/dvl_beams.h"
#include "auv/sim/sensors/multibeam.h"
#include "auv/sim/world/scenario.h"
#include "auv/sim/worldgen/world_generator.h"

namespace auv::sim {
namespace {

namespace fs = std::filesystem;
using Eigen::Vector3d;
using Eigen::Vector3f;

constexpr double kTestDetail = 0.1;  // coarse grids and texels: fast, same layout

fs::path testFolder() {
  static const fs::path folder =
      fs::temp_directory_path() / ("auv_worldgen_test_" + std::to_string(::getpid()));
  return folder;
}

class CleanUp : public ::testing::Environment {
 public:
  void TearDown() override { fs::remove_all(testFolder()); }
};
const auto* const kCleanUp = ::testing::AddGlobalTestEnvironment(new CleanUp);

struct LoadedWorld {
  GeneratedWorld generated;
  Scenario scenario;
  Mesh mesh;  // world NED
  std::unique_ptr<RayCaster> caster;
};

// Each world generated, written and loaded once for all tests.
const LoadedWorld& loaded(const std::string& name) {
  static std::map<std::string, std::unique_ptr<LoadedWorld>> worlds;
  auto& slot = worlds[name];
  if (!slot) {
    slot = std::make_unique<LoadedWorld>();
    WorldGenOptions options;
    // Other layouts: AUV_WORLDGEN_TEST_SEED=n, AUV_WORLDGEN_TEST_DETAIL=x (the checks must hold
    // for every seed and detail).
    const char* seed = std::getenv("AUV_WORLDGEN_TEST_SEED");
    const char* detail = std::getenv("AUV_WORLDGEN_TEST_DETAIL");
    options.seed = seed ? std::strtoull(seed, nullptr, 10) : 5;
    options.detail = detail ? std::strtod(detail, nullptr) : kTestDetail;
    slot->generated = generateWorld(name, options);
    const std::string yaml = writeWorld(slot->generated, (testFolder() / name).string());
    slot->scenario = loadScenario(yaml);
    slot->mesh = loadWorldMesh(slot->scenario);
    slot->caster = std::make_unique<RayCaster>(slot->mesh);
  }
  return *slot;
}

bool clearWithin(const RayCaster& caster, const Vector3d& p, double radius) {
  Vector3f closest;
  uint32_t triangle = 0;
  return !caster.closestPoint(p.cast<float>(), static_cast<float>(radius), closest, triangle);
}

// Inside a solid if any of 14 rays first meets the back of a surface.
bool insideSolid(const LoadedWorld& world, const Vector3d& p) {
  for (int dx = -1; dx <= 1; ++dx) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dz = -1; dz <= 1; ++dz) {
        const int nonzero = (dx != 0) + (dy != 0) + (dz != 0);
        if (nonzero != 1 && nonzero != 3) continue;
        const Vector3f direction = Vector3f(dx, dy, dz).normalized();
        const RayHit hit = world.caster->cast(p.cast<float>(), direction, 500.0f);
        if (!hit.hit()) continue;
        const Eigen::Vector3i& tri = world.mesh.triangles[hit.triangle];
        const Vector3f& a = world.mesh.vertices[tri[0]];
        const Vector3f outward =
            (world.mesh.vertices[tri[1]] - a).cross(world.mesh.vertices[tri[2]] - a);
        if (outward.dot(direction) > 0.0f) return true;
      }
    }
  }
  return false;
}

// Distances along the ray to every surface it crosses (up to `range`).
std::vector<double> crossings(const RayCaster& caster, const Vector3d& origin,
                              const Vector3d& direction, double range) {
  std::vector<double> distances;
  double t = 0.0;
  while (t < range) {
    const RayHit hit = caster.cast(origin.cast<float>(), direction.cast<float>(),
                                   static_cast<float>(range), static_cast<float>(t + 1e-3));
    if (!hit.hit()) break;
    distances.push_back(hit.distance);
    t = hit.distance;
  }
  return distances;
}

class AllWorlds : public ::testing::TestWithParam<std::string> {};

TEST_P(AllWorlds, StartAndGoalsAreInOpenWaterWithTwoMetresClearance) {
  const LoadedWorld& world = loaded(GetParam());
  std::vector<std::pair<std::string, Vector3d>> points{{"start", world.scenario.start_position}};
  for (const MissionQuery& q : world.scenario.queries) points.emplace_back(q.name, q.goal);
  ASSERT_GE(world.scenario.queries.size(), 2u);
  for (const auto& [label, p] : points) {
    EXPECT_TRUE(clearWithin(*world.caster, p, 2.0)) << GetParam() << " " << label;
    EXPECT_FALSE(insideSolid(world, p)) << GetParam() << " " << label;
    EXPECT_GT(p.z(), 2.0) << label;  // submerged
    EXPECT_LT(p.z(), world.scenario.seabed_depth - 2.0) << label;
  }
}

TEST_P(AllWorlds, ReferenceRoutesAreCollisionFree) {
  const LoadedWorld& world = loaded(GetParam());
  const auto& routes = world.generated.layout.routes;
  ASSERT_EQ(routes.size(), world.generated.queries.size());
  Vector3d from = world.generated.start_position;
  for (size_t q = 0; q < routes.size(); ++q) {
    ASSERT_GE(routes[q].size(), 2u);
    EXPECT_LT((routes[q].front() - from).norm(), 1e-6) << "route " << q << " starts elsewhere";
    EXPECT_LT((routes[q].back() - world.generated.queries[q].goal).norm(), 1e-6);
    for (size_t i = 1; i < routes[q].size(); ++i) {
      const Vector3d a = routes[q][i - 1], b = routes[q][i];
      const int steps = static_cast<int>(std::ceil((b - a).norm() / 0.25)) + 1;
      for (int s = 0; s <= steps; ++s) {
        const Vector3d p = a + (b - a) * (static_cast<double>(s) / steps);
        ASSERT_TRUE(clearWithin(*world.caster, p, 1.5))
            << GetParam() << " route " << q << " blocked near " << p.transpose();
      }
    }
    from = routes[q].back();
  }
}

TEST_P(AllWorlds, WrittenMeshReloadsValidatesAndKeepsItsTexture) {
  const LoadedWorld& world = loaded(GetParam());
  Mesh reloaded = loadMesh(world.scenario.mesh_path);
  const MeshReport report = validateMesh(reloaded);
  const Mesh& original = world.generated.mesh;
  EXPECT_GE(report.triangles + report.removed_degenerate, original.triangles.size());
  EXPECT_LE(report.removed_degenerate, original.triangles.size() / 1000);
  ASSERT_TRUE(reloaded.hasTexture());
  EXPECT_EQ(reloaded.texture.cols, original.texture.cols);
  EXPECT_EQ(reloaded.texture.rows, original.texture.rows);
  EXPECT_EQ(cv::norm(reloaded.texture, original.texture, cv::NORM_INF), 0.0);
  EXPECT_EQ(world.scenario.name, GetParam());
  EXPECT_NEAR(world.scenario.seabed_depth, world.generated.seabed_depth, 1e-9);
}

TEST_P(AllWorlds, MissionModeFitsTheWorldAndRoutesKeepToTheBand) {
  const LoadedWorld& world = loaded(GetParam());
  const MissionPlanning& m = world.scenario.mission;
  EXPECT_EQ(m.fixed_depth, world.generated.mission.fixed_depth);
  EXPECT_EQ(m.min_depth, world.generated.mission.min_depth);
  EXPECT_EQ(m.max_depth, world.generated.mission.max_depth);
  EXPECT_EQ(m.min_altitude, world.generated.mission.min_altitude);
  const bool natural =
      GetParam() == "arch" || GetParam() == "boulder_field" || GetParam() == "leaning_reef";
  EXPECT_EQ(m.fixed_depth, !natural) << "the paper's worlds keep the 2-D mode";
  // 3-D planning comes with 3-D sensing; the paper's worlds keep the profiler alone.
  const MultibeamOptions multibeam = MultibeamOptions::fromScenario(world.scenario.root);
  EXPECT_EQ(multibeam.enabled, natural);
  // Rock above the vehicle (an arch's underside) must be seen, not only the seabed.
  if (natural) EXPECT_LT(multibeam.mount_pitch - 0.5 * multibeam.vertical_aperture, -0.1);
  EXPECT_EQ(DvlBeamsOptions::fromScenario(world.scenario.root).enabled, natural);
  if (m.fixed_depth) {
    // Every route stays in the plane of the start.
    for (const auto& route : world.generated.layout.routes)
      for (const Vector3d& p : route) EXPECT_NEAR(p.z(), world.scenario.start_position.z(), 1e-9);
    return;
  }
  ASSERT_TRUE(m.hasBand());
  EXPECT_GT(m.min_altitude, 0.0);
  for (const auto& route : world.generated.layout.routes) {
    for (size_t i = 1; i < route.size(); ++i) {
      for (int s = 0; s <= 20; ++s) {
        const Vector3d p = route[i - 1] + (route[i] - route[i - 1]) * (s / 20.0);
        EXPECT_GE(p.z(), m.min_depth - 1e-9) << GetParam() << " " << p.transpose();
        EXPECT_LE(p.z(), m.max_depth + 1e-9) << GetParam() << " " << p.transpose();
        const RayHit below = world.caster->cast(p.cast<float>(), Vector3f(0, 0, 1), 50.0f);
        ASSERT_TRUE(below.hit()) << "no seabed under " << p.transpose();
        EXPECT_GE(below.distance, m.min_altitude) << GetParam() << " " << p.transpose();
      }
    }
  }
}

TEST_P(AllWorlds, SameSeedSameWorldOtherSeedOtherWorld) {
  WorldGenOptions options;
  options.detail = 0.03;
  options.seed = 3;
  const GeneratedWorld a = generateWorld(GetParam(), options);
  const GeneratedWorld b = generateWorld(GetParam(), options);
  options.seed = 4;
  const GeneratedWorld c = generateWorld(GetParam(), options);
  EXPECT_TRUE(a.mesh.vertices == b.mesh.vertices);
  EXPECT_TRUE(a.mesh.triangles == b.mesh.triangles);
  EXPECT_EQ(scenarioYaml(a, "x.obj"), scenarioYaml(b, "x.obj"));
  EXPECT_FALSE(a.mesh.vertices == c.mesh.vertices);
}

INSTANTIATE_TEST_SUITE_P(Worldgen, AllWorlds,
                         ::testing::Values("arch", "boulder_field", "breakwater", "canyon",
                                           "dead_end_bay", "leaning_reef"));

TEST(BreakwaterTest, BlocksAre14_5By12MetresWithGapsOfTwoToFourMetres) {
  const LoadedWorld& world = loaded("breakwater");
  const auto& blocks = world.generated.layout.blocks;
  ASSERT_EQ(blocks.size(), 5u);
  const double depth = 4.0;
  // Along the row (east-west), through the blocks' common middle.
  double mid_x = 0.0, west = 1e9, east = -1e9;
  for (const auto& b : blocks)
    mid_x += b.center().x() / blocks.size(), west = std::min(west, b.min().y()),
                                             east = std::max(east, b.max().y());
  const std::vector<double> hits = crossings(*world.caster, Vector3d(mid_x, west - 10.0, depth),
                                             Vector3d(0, 1, 0), east - west + 20.0);
  ASSERT_EQ(hits.size(), 10u);
  double narrowest = 1e9, widest = 0.0;
  for (int i = 0; i < 5; ++i) {
    EXPECT_NEAR(hits[2 * i + 1] - hits[2 * i], 14.5, 0.02) << "block " << i;
    if (i < 4) {
      const double gap = hits[2 * i + 2] - hits[2 * i + 1];
      EXPECT_GE(gap, 2.0 - 0.02);
      EXPECT_LE(gap, 4.0 + 0.02);
      narrowest = std::min(narrowest, gap);
      widest = std::max(widest, gap);
    }
  }
  EXPECT_LE(narrowest, 2.4 + 0.02);  // some gaps are narrow
  EXPECT_GE(widest, 3.5 - 0.02);
  // Across each block (north-south), and up to above the surface.
  for (const auto& b : blocks) {
    const std::vector<double> across =
        crossings(*world.caster, Vector3d(b.min().x() - 10.0, b.center().y(), depth),
                  Vector3d(1, 0, 0), 30.0);
    ASSERT_GE(across.size(), 2u);
    EXPECT_NEAR(across[1] - across[0], 12.0, 0.02);
    const RayHit top = world.caster->cast(Vector3f(b.center().x(), b.center().y(), -5.0f),
                                          Vector3f(0, 0, 1), 20.0f);
    ASSERT_TRUE(top.hit());
    EXPECT_LT(-5.0 + top.distance, 0.0) << "the block should rise above the surface";
  }
}

TEST(BreakwaterTest, StraightLineFromStartToGoalRunsIntoTheRow) {
  const LoadedWorld& world = loaded("breakwater");
  const Vector3d start = world.scenario.start_position, goal = world.scenario.queries[0].goal;
  EXPECT_TRUE(world.caster->occluded(start.cast<float>(), (goal - start).normalized().cast<float>(),
                                     static_cast<float>((goal - start).norm())));
}

TEST(CanyonTest, WidthAtThreeMetresStaysWithinFourToEightMetresAlongThirtyMetres) {
  const LoadedWorld& world = loaded("canyon");
  const WorldLayout& layout = world.generated.layout;
  ASSERT_GE(layout.canyon_axis.size(), 25u);
  const double length = (layout.canyon_axis.back() - layout.canyon_axis.front()).norm();
  EXPECT_GE(length, 30.0 - 2.0);  // the axis stops 1 m short of each end
  EXPECT_LE(length, 40.0);
  EXPECT_GE(layout.canyon_min_width, 4.0);
  EXPECT_LE(layout.canyon_max_width, 8.0);
  double narrowest = 1e9, widest = 0.0;
  for (const Vector3d& p : layout.canyon_axis) {
    EXPECT_NEAR(p.z(), 3.0, 1e-9);
    const RayHit east = world.caster->cast(p.cast<float>(), Vector3f(0, 1, 0), 10.0f);
    const RayHit west = world.caster->cast(p.cast<float>(), Vector3f(0, -1, 0), 10.0f);
    ASSERT_TRUE(east.hit() && west.hit()) << "no wall beside " << p.transpose();
    const double width = east.distance + west.distance;
    EXPECT_GE(width, layout.canyon_min_width - 0.05) << p.transpose();
    EXPECT_LE(width, layout.canyon_max_width + 0.05) << p.transpose();
    narrowest = std::min(narrowest, width);
    widest = std::max(widest, width);
  }
  EXPECT_GT(widest - narrowest, 0.3);  // a natural canyon, not a straight channel
}

TEST(CanyonTest, CircumnavigationGoalIsBehindTheOuterRock) {
  const LoadedWorld& world = loaded("canyon");
  const auto& q = world.scenario.queries;
  ASSERT_EQ(q.size(), 3u);
  EXPECT_EQ(q[0].name, "traverse");
  EXPECT_EQ(q[1].name, "circumnavigate_outer_rock");
  EXPECT_EQ(q[2].name, "traverse_again");
  EXPECT_LT((q[2].goal - q[0].goal).norm(), 1e-9);
  const Vector3d a = q[0].goal, b = q[1].goal;
  EXPECT_TRUE(world.caster->occluded(a.cast<float>(), (b - a).normalized().cast<float>(),
                                     static_cast<float>((b - a).norm())));
  // The second goal is back towards the start (south of the canyon's far end).
  EXPECT_LT((b - world.scenario.start_position).norm(), (a - world.scenario.start_position).norm());
}

TEST(DeadEndBayTest, DirectRouteEndsInTheBay) {
  const LoadedWorld& world = loaded("dead_end_bay");
  const Vector3d start = world.scenario.start_position, goal = world.scenario.queries[0].goal;
  const Vector3d direction = (goal - start).normalized();
  const RayHit hit = world.caster->cast(start.cast<float>(), direction.cast<float>(),
                                        static_cast<float>((goal - start).norm()));
  ASSERT_TRUE(hit.hit());
  // The wall it meets is the bay's closed end: open water on both sides of the line before it.
  const Vector3d inside_bay = start + direction * (hit.distance - 6.0);
  const Vector3d side(-direction.y(), direction.x(), 0.0);
  const RayHit left = world.caster->cast(inside_bay.cast<float>(), side.cast<float>(), 30.0f);
  const RayHit right = world.caster->cast(inside_bay.cast<float>(), (-side).cast<float>(), 30.0f);
  ASSERT_TRUE(left.hit() && right.hit()) << "the line should end between the bay's arms";
  EXPECT_GT(left.distance + right.distance, 6.0);  // wide enough to enter
  EXPECT_LT(left.distance + right.distance, 25.0);
}

// Depth of the first surface met looking down from 10 m above the sea at NED (x, y) (negative:
// above the surface), or 1e9 for none.
double firstRockDepth(const LoadedWorld& world, double x, double y) {
  const RayHit hit = world.caster->cast(Vector3f(x, y, -10.0f), Vector3f(0, 0, 1), 60.0f);
  return hit.hit() ? hit.distance - 10.0 : 1e9;
}

TEST(BoulderFieldTest, ManyTopsJustBelowTheStartDepthAndTallOnesToGoRound) {
  const LoadedWorld& world = loaded("boulder_field");
  const double start_depth = world.scenario.start_position.z();
  const WorldLayout& layout = world.generated.layout;
  ASSERT_GE(layout.shallow_boulder_tops.size(), 6u);
  int shallow = 0;
  for (const Vector3d& top : layout.shallow_boulder_tops) {
    const double depth = firstRockDepth(world, top.x(), top.y());
    shallow += depth > start_depth && depth <= start_depth + 1.5;
  }
  // A vehicle held at the start depth passes over these with less than 1.5 m of altitude.
  EXPECT_GE(shallow, 6) << "of " << layout.shallow_boulder_tops.size();
  ASSERT_GE(layout.tall_boulder_tops.size(), 2u);
  for (const Vector3d& top : layout.tall_boulder_tops) {
    // Too shallow to pass over inside the band at the planner's 1.2 m clearance.
    const double depth = firstRockDepth(world, top.x(), top.y());
    EXPECT_LT(depth, world.scenario.mission.min_depth + 1.2) << top.transpose();
  }
  // The first query's straight line at the start depth runs into rock.
  const Vector3d start = world.scenario.start_position, goal = world.scenario.queries[0].goal;
  EXPECT_TRUE(world.caster->occluded(start.cast<float>(), (goal - start).normalized().cast<float>(),
                                     static_cast<float>((goal - start).norm())));
}

TEST(ArchTest, RockAboveOpenWaterOnTheRouteAndAWallBeyond) {
  const LoadedWorld& world = loaded("arch");
  const WorldLayout& layout = world.generated.layout;
  const Vector3d under = layout.arch_under;
  EXPECT_TRUE(clearWithin(*world.caster, under, 2.0));
  EXPECT_FALSE(insideSolid(world, under));
  // Surfacing from under the span meets rock, which reaches above the surface.
  const std::vector<double> up =
      crossings(*world.caster, under, Vector3d(0, 0, -1), under.z() + 5.0);
  ASSERT_GE(up.size(), 2u) << "no span above the passage";
  EXPECT_GT(under.z() - up[0], 2.0) << "the span's underside should be below 2 m depth";
  EXPECT_LT(under.z() - up[0], 6.0);
  EXPECT_LT(under.z() - up[1], 0.0) << "the span should rise above the surface";
  // A route passes under the span.
  bool on_route = false;
  for (const auto& route : layout.routes)
    for (const Vector3d& p : route) on_route |= (p - under).norm() < 1e-6;
  EXPECT_TRUE(on_route);
  // Flying on through the passage meets the wall beyond it.
  const RayHit beyond =
      world.caster->cast(under.cast<float>(), layout.arch_through.cast<float>(), 40.0f);
  ASSERT_TRUE(beyond.hit());
  EXPECT_GT(beyond.distance, 10.0);
  EXPECT_LT(beyond.distance, 25.0);
  // At the start depth the arch is closed: the straight line to the passage meets the span.
  const Vector3d start = world.scenario.start_position;
  const Vector3d level(under.x() + 3.0, under.y(), start.z());
  EXPECT_TRUE(world.caster->occluded(start.cast<float>(),
                                     (level - start).normalized().cast<float>(),
                                     static_cast<float>((level - start).norm())));
}

TEST(LeaningReefTest, FaceLeansOutBelowTheNavigationDepthOverAnUndercut) {
  const LoadedWorld& world = loaded("leaning_reef");
  const WorldLayout& layout = world.generated.layout;
  ASSERT_GE(layout.reef_stations.size(), 5u);
  int undercut = 0;
  for (const Vector3d& station : layout.reef_stations) {
    auto faceAt = [&](double depth) {
      const Vector3d origin(station.x(), station.y(), depth);
      const RayHit hit =
          world.caster->cast(origin.cast<float>(), layout.reef_towards.cast<float>(), 40.0f);
      return hit.hit() ? static_cast<double>(hit.distance) : 1e9;
    };
    const double top = faceAt(1.0), navigation = faceAt(3.0);
    double closest = 1e9, closest_depth = 0.0;
    for (double depth = 1.0; depth <= 9.0; depth += 0.25) {
      if (faceAt(depth) < closest) closest = faceAt(depth), closest_depth = depth;
    }
    // The face at depth is well out from where it is near the surface and at 3 m.
    EXPECT_GT(top - closest, 3.0) << station.transpose();
    EXPECT_GT(navigation - closest, 2.0) << station.transpose();
    EXPECT_GT(closest_depth, 4.5) << station.transpose();
    // Under the lip: open water with rock straight above.
    const double deeper = closest_depth + 2.0;
    if (faceAt(deeper) < closest + 1.0) continue;
    const Vector3d below_lip =
        Vector3d(station.x(), station.y(), deeper) + layout.reef_towards * (closest + 0.4);
    const RayHit up = world.caster->cast(below_lip.cast<float>(), Vector3f(0, 0, -1), 4.0f);
    undercut += up.hit() && !insideSolid(world, below_lip);
  }
  EXPECT_GE(undercut, 4) << "of " << layout.reef_stations.size();
}

TEST(WorldgenTest, SameSeedSameWorldOtherSeedOtherRock) {
  WorldGenOptions options;
  options.detail = 0.05;
  options.seed = 3;
  const GeneratedWorld a = generateWorld("canyon", options);
  const GeneratedWorld b = generateWorld("canyon", options);
  options.seed = 4;
  const GeneratedWorld c = generateWorld("canyon", options);
  ASSERT_EQ(a.mesh.vertices.size(), b.mesh.vertices.size());
  EXPECT_TRUE(a.mesh.vertices == b.mesh.vertices);
  EXPECT_TRUE(a.mesh.triangles == b.mesh.triangles);
  EXPECT_TRUE(a.mesh.triangle_uvs == b.mesh.triangle_uvs);
  EXPECT_EQ(cv::norm(a.mesh.texture, b.mesh.texture, cv::NORM_INF), 0.0);
  EXPECT_EQ(scenarioYaml(a, "x.obj"), scenarioYaml(b, "x.obj"));
  EXPECT_FALSE(a.mesh.vertices == c.mesh.vertices);
  EXPECT_NE(scenarioYaml(a, "x.obj"), scenarioYaml(c, "x.obj"));
}

TEST(WorldgenTest, DefaultCanyonIsModestAndItsRockTextureRichForSift) {
  const GeneratedWorld world = generateWorld("canyon", WorldGenOptions());
  EXPECT_LE(world.stats.triangles, 300000u);
  EXPECT_LE(world.mesh.texture.cols, 4096);
  EXPECT_LE(world.mesh.texture.rows, 4096);
  EXPECT_LE(world.stats.structure_texel, 0.0215);  // about 2 cm/texel on the rock
  // The atlas's first shelf holds its tallest cells: rock walls.
  const cv::Mat crop = world.mesh.texture(cv::Rect(0, 0, 1024, 1024));
  cv::Mat gray;
  cv::cvtColor(crop, gray, cv::COLOR_BGR2GRAY);
  std::vector<cv::KeyPoint> keypoints;
  cv::SIFT::create()->detect(gray, keypoints);
  EXPECT_GE(keypoints.size(), 500u);
}

TEST(WorldgenTest, UnknownWorldsAndBadOptionsAreConfigErrors) {
  try {
    generateWorld("canyno");
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("did you mean 'canyon'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("breakwater"), std::string::npos) << e.what();
  }
  WorldGenOptions options;
  options.detail = 0.0;
  EXPECT_THROW(generateWorld("canyon", options), ConfigError);
  EXPECT_EQ(availableWorlds(),
            (std::vector<std::string>{"arch", "boulder_field", "breakwater", "canyon",
                                      "dead_end_bay", "leaning_reef"}));
}

}  // namespace
}  // namespace auv::sim
