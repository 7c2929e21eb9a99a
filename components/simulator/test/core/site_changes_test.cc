// Sites that change between visits: each kind of change on a flat seabed with a loose block,
// checked against what it must do to the mesh, and the true change (regions, distances,
// volumes) measured from the two meshes against analytic values; the scenario's `changes:`
// read strictly.
#include "auv/sim/world/site_changes.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "auv/sim/raycast/ray_caster.h"
#include "auv/sim/world/change_truth.h"
#include "auv/sim/world/rock.h"
#include "auv/sim/world/scenario.h"
#include "test_meshes.h"

namespace auv::sim {
namespace {

namespace fs = std::filesystem;

/// A flat seabed at 8 m depth (NED), 20 x 20 m in 0.5 m cells, facing up (-z).
Mesh seabed() {
  Mesh m;
  const int n = 40;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j)
      m.vertices.emplace_back(-10.0f + 0.5f * i, -10.0f + 0.5f * j, 8.0f);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const int a = i * (n + 1) + j, b = a + n + 1;
      m.triangles.emplace_back(a, a + 1, b);  // (x, y) -> (x, y + 1) -> (x + 1, y): normal -z
      m.triangles.emplace_back(a + 1, b + 1, b);
    }
  }
  m.vertex_colors.assign(m.vertices.size(), Eigen::Vector3f(0.4f, 0.5f, 0.4f));
  m.source = "seabed";
  return m;
}

/// The seabed with a loose 1 x 1 x 0.6 m block standing on it at (3, 0).
Mesh site() {
  Mesh m = seabed();
  appendMesh(m, test::box({2.5f, -0.5f, 7.4f}, {3.5f, 0.5f, 8.0f}));
  return m;
}

SiteChange change(SiteChangeType type, const std::string& name, const Eigen::Vector3d& center,
                  double radius) {
  SiteChange c;
  c.type = type;
  c.name = name;
  c.center = center;
  c.radius = radius;
  return c;
}

ChangeTruth truthOf(const Mesh& before, const std::vector<SiteChange>& changes,
                    Mesh* after_out = nullptr) {
  Mesh after = before;
  const std::vector<AppliedChange> applied = applySiteChanges(after, changes, "test.yaml");
  const ChangeTruth truth = measureChangeTruth(before, after, applied);
  if (after_out) *after_out = after;
  return truth;
}

Eigen::Vector3f normalOf(const Mesh& m, const Eigen::Vector3i& t) {
  return (m.vertices[t[1]] - m.vertices[t[0]]).cross(m.vertices[t[2]] - m.vertices[t[0]]);
}

TEST(SiteChangesTest, SeabedFixtureFacesUp) {
  const Mesh m = seabed();
  EXPECT_LT(normalOf(m, m.triangles[0]).z(), 0.0f);
  EXPECT_LT(normalOf(m, m.triangles[1]).z(), 0.0f);
}

TEST(SiteChangesTest, RemoveTakesTheLooseBlockOnlyAndTheTruthMeasuresItsVolume) {
  const Mesh before = site();
  Mesh after;
  const ChangeTruth truth =
      truthOf(before, {change(SiteChangeType::kRemove, "gone", {3, 0, 7.7}, 1.0)}, &after);
  EXPECT_EQ(after.triangles.size(), before.triangles.size() - 12);
  ASSERT_EQ(truth.regions.size(), 1u);
  const ChangeTruthRegion& r = truth.regions[0];
  EXPECT_EQ(r.name, "gone");
  EXPECT_NEAR(r.volume_lost_m3, 0.6, 0.03);  // 1 x 1 x 0.6 m by 2 cm columns
  EXPECT_NEAR(r.volume_gained_m3, 0.0, 1e-9);
  EXPECT_NEAR(r.max_distance_m, -0.6, 0.02);  // the block's top, 0.6 m above the seabed
  EXPECT_NEAR(r.centroid.x(), 3.0, 0.05);
  // Lost surface: the top (1 m²) and the four sides (4 x 0.6 m²), seen on the earlier world.
  EXPECT_NEAR(r.area_m2, 3.4, 0.25);
  for (float d : truth.distances) EXPECT_LT(d, 0.0f);
}

TEST(SiteChangesTest, RemoveOrMoveWithoutALooseRockInsideNamesTheEntry) {
  Mesh mesh = site();
  try {
    applySiteChanges(mesh, {change(SiteChangeType::kRemove, "nothing", {-5, -5, 8}, 1.0)},
                     "s.yaml");
    FAIL() << "removing the seabed's middle was accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("s.yaml: changes[0] (nothing).center: no loose rock"),
              std::string::npos)
        << e.what();
  }
  // A sphere cutting the block in half does not hold it wholly: not loose inside it.
  EXPECT_TRUE(looseRocksWithin(mesh, {3, 0, 7.7}, 0.5).empty());
  EXPECT_EQ(looseRocksWithin(mesh, {3, 0, 7.7}, 0.9).size(), 1u);
}

TEST(SiteChangesTest, MoveGivesWhereItWasAndWhereItIs) {
  SiteChange moved = change(SiteChangeType::kMove, "pushed", {3, 0, 7.7}, 1.0);
  moved.translation = {0, 3, 0};
  Mesh after;
  const ChangeTruth truth = truthOf(site(), {moved}, &after);
  ASSERT_EQ(truth.regions.size(), 2u);
  EXPECT_EQ(truth.regions[0].name, "pushed/from");
  EXPECT_EQ(truth.regions[1].name, "pushed/to");
  EXPECT_EQ(truth.regions[1].change, "pushed");
  EXPECT_NEAR(truth.regions[0].volume_lost_m3, 0.6, 0.03);
  EXPECT_NEAR(truth.regions[1].volume_gained_m3, 0.6, 0.03);
  EXPECT_NEAR(truth.regions[1].centroid.y(), 3.0, 0.05);
  EXPECT_NEAR(truth.regions[1].max_distance_m, 0.6, 0.02);
  const RayCaster caster(after);
  EXPECT_NEAR(caster.cast({3, 3, 0}, {0, 0, 1}, 20).distance, 7.4f, 1e-3f);  // the block's top
  EXPECT_NEAR(caster.cast({3, 0, 0}, {0, 0, 1}, 20).distance, 8.0f, 1e-3f);  // seabed where it was
}

/// Volume of the plateau patch: thickness times the weight integrated over the disc.
double patchVolume(double radius, double thickness) {
  double volume = 0.0;
  const double dr = radius / 20000.0;
  for (double r = 0.5 * dr; r < radius; r += dr) {
    const double inner = 0.7 * radius;
    const double w =
        r <= inner ? 1.0 : 0.5 * (1.0 + std::cos(M_PI * (r - inner) / (radius - inner)));
    volume += w * 2.0 * M_PI * r * dr;
  }
  return volume * thickness;
}

TEST(SiteChangesTest, GrowthRaisesThePatchByItsThicknessWithoutOpeningTheSurface) {
  SiteChange grow = change(SiteChangeType::kGrow, "growth", {-4, 4, 8}, 1.5);
  grow.thickness = 0.2;
  Mesh after;
  const ChangeTruth truth = truthOf(site(), {grow}, &after);
  ASSERT_EQ(truth.regions.size(), 1u);
  const ChangeTruthRegion& r = truth.regions[0];
  EXPECT_NEAR(r.volume_gained_m3, patchVolume(1.5, 0.2), 0.02 * patchVolume(1.5, 0.2));
  EXPECT_NEAR(r.max_distance_m, 0.2, 0.005);
  const RayCaster caster(after);
  // The plateau is 0.2 m up; every ray from above meets the surface (no crack at the rim).
  EXPECT_NEAR(caster.cast({-4, 4, 0}, {0, 0, 1}, 20).distance, 7.8f, 1e-3f);
  int misses = 0;
  for (float x = -6.0f; x <= -2.0f; x += 0.013f)
    for (float y = 2.0f; y <= 6.0f; y += 0.017f)
      misses += !caster.cast({x, y, 0}, {0, 0, 1}, 20).hit();
  EXPECT_EQ(misses, 0);

  SiteChange scour = grow;
  scour.name = "scour";
  scour.thickness = -0.2;
  const ChangeTruth eroded = truthOf(site(), {scour});
  EXPECT_NEAR(eroded.regions[0].volume_lost_m3, patchVolume(1.5, 0.2),
              0.02 * patchVolume(1.5, 0.2));
  EXPECT_NEAR(eroded.regions[0].max_distance_m, -0.2, 0.005);
}

TEST(SiteChangesTest, AlbedoChangesTheColourNotTheShapeAndLeavesTheEarlierVisitAlone) {
  // Textured seabed: the earlier visit's copy shares the image until the change clones it.
  Mesh textured = seabed();
  textured.vertex_colors.clear();
  textured.texture = cv::Mat(256, 256, CV_8UC3, cv::Scalar(60, 80, 70));
  for (const Eigen::Vector3i& t : textured.triangles)
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3f& v = textured.vertices[t[k]];
      textured.triangle_uvs.emplace_back((v.x() + 10.0f) / 20.0f, (v.y() + 10.0f) / 20.0f);
    }
  SiteChange bleach = change(SiteChangeType::kAlbedo, "bleached", {0, 0, 8}, 1.0);
  bleach.color = {1.0, 1.0, 1.0};
  bleach.strength = 1.0;
  Mesh after;
  const ChangeTruth truth = truthOf(textured, {bleach}, &after);
  const cv::Vec3b centre = after.texture.at<cv::Vec3b>(128, 128);
  EXPECT_EQ(centre, cv::Vec3b(255, 255, 255));
  EXPECT_EQ(after.texture.at<cv::Vec3b>(20, 20), cv::Vec3b(60, 80, 70));  // far from the patch
  EXPECT_EQ(textured.texture.at<cv::Vec3b>(128, 128), cv::Vec3b(60, 80, 70));
  EXPECT_EQ(after.vertices, textured.vertices);
  ASSERT_EQ(truth.regions.size(), 1u);
  EXPECT_FALSE(truth.regions[0].geometric);
  EXPECT_NEAR(truth.regions[0].area_m2, M_PI * 0.7 * 0.7, 0.1);
  for (float d : truth.distances) EXPECT_EQ(d, 0.0f);
}

TEST(SiteChangesTest, AddedRockIsClosedFacesOutAndStandsOnTheSurface) {
  const Mesh world = seabed();
  const Mesh rock = makeRock({-3, -3, 8}, {1.0, 0.8, 0.6}, 30.0, 7, world);
  Eigen::Vector3f centre = Eigen::Vector3f::Zero();
  for (const Eigen::Vector3f& v : rock.vertices) centre += v;
  centre /= static_cast<float>(rock.vertices.size());
  double volume = 0.0;  // divergence theorem: positive only if every face points out
  for (const Eigen::Vector3i& t : rock.triangles) {
    EXPECT_GT(normalOf(rock, t).dot(rock.vertices[t[0]] - centre), 0.0f);
    volume += rock.vertices[t[0]].cast<double>().dot(
                  rock.vertices[t[1]].cast<double>().cross(rock.vertices[t[2]].cast<double>())) /
              6.0;
  }
  const double ellipsoid = 4.0 / 3.0 * M_PI * 0.5 * 0.4 * 0.3;
  EXPECT_NEAR(volume, ellipsoid, 0.2 * ellipsoid);
  SiteChange add;
  add.type = SiteChangeType::kAdd;
  add.name = "block";
  add.center = {-3, -3, 8};
  add.size = {1.0, 0.8, 0.6};
  add.yaw_deg = 30.0;
  add.seed = 7;
  Mesh after;
  const ChangeTruth truth = truthOf(world, {add}, &after);
  ASSERT_EQ(truth.regions.size(), 1u);
  // Seen from above: the columns from the rock's top down to the seabed over its widest
  // section (the undercut below the bulge included), for the smooth ellipsoid
  // pi a b (0.4 H + 2/3 c) with its centre 0.4 H above the seabed; the lumps move it a little.
  const double columns = M_PI * 0.5 * 0.4 * (0.4 * 0.6 + 2.0 / 3.0 * 0.3);
  EXPECT_NEAR(truth.regions[0].volume_gained_m3, columns, 0.1 * columns);
  EXPECT_GT(truth.regions[0].volume_gained_m3, 0.97 * volume);
  EXPECT_GT(truth.regions[0].max_distance_m, 0.45);
  EXPECT_LT(truth.regions[0].max_distance_m, 0.7);
}

TEST(SiteChangesTest, TruthFilesAreWrittenWhole) {
  SiteChange grow = change(SiteChangeType::kGrow, "growth", {-4, 4, 8}, 1.0);
  grow.thickness = 0.15;
  const ChangeTruth truth =
      truthOf(site(), {grow, change(SiteChangeType::kRemove, "gone", {3, 0, 7.7}, 1.0)});
  const fs::path dir = fs::path(testing::TempDir()) / "auv_change_truth";
  fs::remove_all(dir);
  writeChangeTruth(truth, dir.string(), "site.yaml");
  const nlohmann::json doc = nlohmann::json::parse(std::ifstream(dir / "changes.json"));
  EXPECT_EQ(doc["format"], "auv-sim-changes 1");
  ASSERT_EQ(doc["regions"].size(), 2u);
  EXPECT_EQ(doc["regions"][1]["type"], "remove");
  EXPECT_EQ(doc["regions"][0]["points"].get<size_t>() + doc["regions"][1]["points"].get<size_t>(),
            truth.points.size());
  std::ifstream ply(dir / "changes.ply", std::ios::binary);
  std::string line, header;
  while (std::getline(ply, line) && line != "end_header") header += line + "\n";
  EXPECT_NE(header.find("element vertex " + std::to_string(truth.points.size())),
            std::string::npos);
  const auto body_start = ply.tellg();
  ply.seekg(0, std::ios::end);
  EXPECT_EQ(static_cast<size_t>(ply.tellg() - body_start), truth.points.size() * 20u);
  EXPECT_FALSE(fs::exists(dir / "changes.json.incomplete"));
}

class ChangesSectionTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(testing::TempDir()) / "auv_changes_section";
    fs::create_directories(dir_);
    saveMesh(site(), (dir_ / "site.ply").string());
  }
  std::string errorOf(const std::string& changes) {
    const std::string path = (dir_ / "scenario.yaml").string();
    std::ofstream(path) << "world: {mesh: site.ply, up_axis: z, seabed_depth: 10}\n"
                        << "changes:\n"
                        << changes;
    try {
      loadWorldMesh(loadScenario(path));
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "";
  }
  fs::path dir_;
};

TEST_F(ChangesSectionTest, BadEntriesNameTheFileAndTheField) {
  EXPECT_NE(errorOf("  - {type: grown, center: [0, 0, 8]}\n").find("changes[0].type: expected add"),
            std::string::npos);
  EXPECT_NE(errorOf("  - {type: grow, center: [0, 0, 8], radius: 1}\n")
                .find("changes[0].thickness: missing"),
            std::string::npos);
  EXPECT_NE(errorOf("  - {type: grow, center: [0, 0, 8], radius: 1, thickness: 0.8}\n")
                .find("changes[0].thickness"),
            std::string::npos);
  EXPECT_NE(errorOf("  - {type: add, size: [1, 1, 1]}\n").find("changes[0].position: missing"),
            std::string::npos);
  EXPECT_NE(
      errorOf("  - {type: move, center: [3, 0, -7.7], radius: 1}\n").find("changes[0].translation"),
      std::string::npos);
  EXPECT_NE(errorOf("  - {name: a, type: albedo, center: [0, 0, -8]}\n"
                    "  - {name: a, type: albedo, center: [1, 0, -8]}\n")
                .find("changes[1].name: 'a' is used twice"),
            std::string::npos);
  EXPECT_NE(errorOf("  - {type: add, position: [0, 0, -8], thickness: 1}\n").find("thickness"),
            std::string::npos);
  const std::string where = errorOf("  - {type: remove, center: [-5, 5, -8], radius: 1}\n");
  EXPECT_NE(where.find("scenario.yaml: changes[0] (change1).center: no loose rock"),
            std::string::npos)
      << where;
  // A good section loads: up_axis z maps the block's top (z = 7.4 in the file) to depth -7.4.
  EXPECT_EQ(errorOf("  - {type: remove, center: [3, 0, -7.7], radius: 1}\n"), "");
}

}  // namespace
}  // namespace auv::sim
