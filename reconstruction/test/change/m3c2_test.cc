// M3C2 on synthetic pairs with analytic answers: parallel planes, concentric spheres, a step,
// no change with noise (about 5 % significant at 95 %), the registration error inside the
// level of detection, points of one depth map counted as one measurement, a surface lying along
// the cylinder, too few points, and the option checks.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "auv/recon/change/m3c2.h"
#include "auv/recon/common/stage_error.h"

namespace auv::recon::change {
namespace {

constexpr double kPi = 3.14159265358979323846;

/// A square of jittered grid points (spacing `step`) at height z = height(x, y) + noise.
template <class Height>
std::vector<Eigen::Vector3d> surface(double half_size, double step, Height height, double noise,
                                     unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.3 * step, 0.3 * step);
  std::normal_distribution<double> gauss(0.0, noise);
  std::vector<Eigen::Vector3d> points;
  for (double x = -half_size; x <= half_size; x += step) {
    for (double y = -half_size; y <= half_size; y += step) {
      const double px = x + jitter(rng), py = y + jitter(rng);
      points.emplace_back(px, py, height(px, py) + (noise > 0 ? gauss(rng) : 0.0));
    }
  }
  return points;
}

std::vector<Eigen::Vector3d> plane(double z, double noise, unsigned seed) {
  return surface(
      5.0, 0.05, [z](double, double) { return z; }, noise, seed);
}

/// Points spread evenly over a sphere (Fibonacci lattice).
std::vector<Eigen::Vector3d> sphere(double radius, int count) {
  std::vector<Eigen::Vector3d> points;
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < count; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / count;
    const double r = std::sqrt(1.0 - z * z);
    points.emplace_back(radius * r * std::cos(golden * i), radius * r * std::sin(golden * i),
                        radius * z);
  }
  return points;
}

std::vector<Eigen::Vector3d> grid(double half_size, double step, double z) {
  std::vector<Eigen::Vector3d> points;
  for (double x = -half_size; x <= half_size + 1e-9; x += step) {
    for (double y = -half_size; y <= half_size + 1e-9; y += step) points.emplace_back(x, y, z);
  }
  return points;
}

M3C2Options upwards() {
  M3C2Options options;
  options.orientation = Eigen::Vector3d::UnitZ();
  return options;
}

TEST(M3C2, ParallelPlanesAreTheirOffsetApartWithATightLevelOfDetection) {
  const double noise = 0.01;
  const auto before = plane(0.0, noise, 1);
  const auto after = plane(0.3, noise, 2);
  const auto result = m3c2(before, after, grid(4.0, 0.5, 0.0), upwards());
  ASSERT_FALSE(result.empty());
  for (const M3C2Point& p : result) {
    ASSERT_TRUE(p.valid());
    EXPECT_NEAR(p.normal.z(), 1.0, 1e-3);
    EXPECT_NEAR(p.distance, 0.3, 0.01);
    // About pi 0.25² / 0.05² = 78 points per cloud: LoD ~ 1.96 sqrt(2 0.01² / 78) = 3 mm.
    EXPECT_GT(p.count1, 40);
    EXPECT_NEAR(p.spread1, noise, 0.005);
    EXPECT_LT(p.level_of_detection, 0.01);
    EXPECT_TRUE(p.significant);
  }
  // The orientation sets the sign: seen from below, the second plane is nearer.
  M3C2Options downwards = upwards();
  downwards.orientation = -Eigen::Vector3d::UnitZ();
  EXPECT_NEAR(m3c2(before, after, {{0, 0, 0}}, downwards)[0].distance, -0.3, 0.01);
}

TEST(M3C2, ConcentricSpheresAreTheirRadiiApartAlongOutwardNormals) {
  const auto inner = sphere(5.0, 40000);
  const auto outer = sphere(5.2, 40000);
  const std::vector<Eigen::Vector3d> cores = sphere(5.0, 200);
  M3C2Options options;
  options.max_depth_m = 0.5;
  // Outward hints: the normals' sign follows each core point's own direction.
  const auto result = m3c2(inner, outer, cores, options, cores);
  for (size_t i = 0; i < cores.size(); ++i) {
    ASSERT_TRUE(result[i].valid()) << i;
    EXPECT_GT(result[i].normal.dot(cores[i].normalized()), 0.99);
    EXPECT_NEAR(result[i].distance, 0.2, 0.01) << i;
    EXPECT_TRUE(result[i].significant);
  }
  EXPECT_THROW(m3c2(inner, outer, cores, options, {Eigen::Vector3d::UnitZ()}),
               std::invalid_argument);
}

TEST(M3C2, AStepIsMeasuredOnEachSideAwayFromIt) {
  const auto before = plane(0.0, 0.0, 3);
  const auto after = surface(
      5.0, 0.05, [](double x, double) { return x < 0.0 ? 0.0 : 0.5; }, 0.0, 4);
  M3C2Options options = upwards();
  const auto result = m3c2(before, after, {{-2.0, 0.0, 0.0}, {2.0, 0.0, 0.0}}, options);
  EXPECT_NEAR(result[0].distance, 0.0, 1e-9);
  EXPECT_FALSE(result[0].significant);
  EXPECT_NEAR(result[1].distance, 0.5, 1e-9);
  EXPECT_TRUE(result[1].significant);
  // A cylinder shorter than the step does not reach the raised side: no distance there.
  options.max_depth_m = 0.4;
  const M3C2Point short_cylinder = m3c2(before, after, {{2.0, 0.0, 0.0}}, options)[0];
  EXPECT_FALSE(short_cylinder.valid());
  EXPECT_EQ(short_cylinder.count2, 0);
  EXPECT_FALSE(short_cylinder.significant);
}

TEST(M3C2, WithoutChangeAboutFivePercentOfTheCorePointsAreSignificant) {
  // Independent noise on both epochs, nothing moved: the 95 % level of detection flags ~5 %.
  const auto before = plane(0.0, 0.02, 5);
  const auto after = plane(0.0, 0.02, 6);
  // Core points 0.5 m apart: their cylinders (0.5 m wide) share no points.
  const auto result = m3c2(before, after, grid(4.5, 0.5, 0.0), upwards());
  int significant = 0, valid = 0;
  for (const M3C2Point& p : result) {
    valid += p.valid();
    significant += p.significant;
  }
  ASSERT_EQ(valid, static_cast<int>(result.size()));
  const double share = static_cast<double>(significant) / valid;
  std::printf("no change: %d of %d core points significant\n", significant, valid);
  EXPECT_GT(share, 0.01) << significant << " of " << valid;
  EXPECT_LT(share, 0.12) << significant << " of " << valid;
}

TEST(M3C2, TheRegistrationErrorRaisesTheLevelOfDetection) {
  const auto before = plane(0.0, 0.01, 7);
  const auto after = plane(0.05, 0.01, 8);
  M3C2Options options = upwards();
  const M3C2Point tight = m3c2(before, after, {{0, 0, 0}}, options)[0];
  options.registration_error_m = 0.03;
  const M3C2Point loose = m3c2(before, after, {{0, 0, 0}}, options)[0];
  EXPECT_NEAR(loose.level_of_detection - tight.level_of_detection, 1.96 * 0.03, 1e-12);
  EXPECT_DOUBLE_EQ(loose.distance, tight.distance);
  EXPECT_TRUE(tight.significant);
  EXPECT_FALSE(loose.significant) << "5 cm within a 6 cm registration error is no change";
}

/// A flat site seen by `maps` depth maps, as a fused MVS cloud is: each map samples every 1 m
/// tile (spacing 0.1 m) with an error of its own there (sd 1 cm) and 2 mm of pixel noise; the
/// points' sources are their map's id.
std::pair<std::vector<Eigen::Vector3d>, PointSources> depthMaps(int maps, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> tile_error(0.0, 0.01), pixel(0.0, 0.002);
  std::vector<Eigen::Vector3d> points;
  PointSources sources;
  for (int map = 0; map < maps; ++map) {
    for (int tx = 0; tx < 10; ++tx) {
      for (int ty = 0; ty < 10; ++ty) {
        const double offset = tile_error(rng);
        for (double x = 0.05; x < 1.0; x += 0.1) {
          for (double y = 0.05; y < 1.0; y += 0.1) {
            points.emplace_back(tx + x, ty + y, offset + pixel(rng));
            sources.add({static_cast<uint32_t>(map)});
          }
        }
      }
    }
  }
  return {points, sources};
}

TEST(M3C2, PointsOfOneDepthMapCountAsOneMeasurement) {
  // Nothing moved, but each cylinder's ~100 points rest on five maps: with n = points the LoD
  // shrinks by sqrt(20) and most core points look changed; with n = sources ~5 % do.
  const auto [before, sources1] = depthMaps(5, 21);
  const auto [after, sources2] = depthMaps(5, 22);
  std::vector<Eigen::Vector3d> cores;
  for (int tx = 0; tx < 10; ++tx) {
    for (int ty = 0; ty < 10; ++ty) cores.emplace_back(tx + 0.5, ty + 0.5, 0.0);
  }
  const auto share = [&](const std::vector<M3C2Point>& result) {
    int significant = 0;
    for (const M3C2Point& p : result) significant += p.significant;
    return static_cast<double>(significant) / static_cast<double>(result.size());
  };
  const auto by_points = m3c2(before, after, cores, upwards());
  const auto by_sources = m3c2(before, after, cores, upwards(), {}, &sources1, &sources2);
  EXPECT_EQ(by_sources[0].sources1, 5);
  EXPECT_EQ(by_sources[0].independent2(), 5);
  EXPECT_EQ(by_points[0].sources1, 0);
  EXPECT_GT(by_points[0].independent1(), 50);
  std::printf("correlated maps: %.2f significant with n = points, %.2f with n = sources\n",
              share(by_points), share(by_sources));
  EXPECT_GT(share(by_points), 0.3);
  EXPECT_LT(share(by_sources), 0.15);
  // Sources that do not fit the cloud are refused.
  PointSources short_list = sources1;
  short_list.offsets.pop_back();
  EXPECT_THROW(m3c2(before, after, cores, upwards(), {}, &short_list, &sources2),
               std::invalid_argument);
}

TEST(M3C2, TheCylinderHoldsExactlyThePointsInsideIt) {
  // The search runs in segments along the axis: every point inside counts once, none outside.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> xy(-0.6, 0.6), z(-1.5, 1.5);
  std::vector<Eigen::Vector3d> cloud;
  for (int i = 0; i < 20000; ++i) cloud.emplace_back(xy(rng), xy(rng), z(rng));
  M3C2Options options = upwards();
  options.max_depth_m = 1.1;  // not a multiple of the segment length
  const M3C2Point p = m3c2(plane(0.0, 0.0, 12), cloud, {{0, 0, 0}}, options)[0];
  int inside = 0;
  for (const Eigen::Vector3d& q : cloud) {
    inside += std::hypot(q.x(), q.y()) <= 0.25 && std::abs(q.z()) <= 1.1;
  }
  EXPECT_EQ(p.count2, inside);
}

/// A wall x = 0 facing +x (y, z within ±2 m, every 2 cm) with its normals; `covered_below`
/// leaves out the wall under that z (hidden behind a block).
void addWall(std::vector<Eigen::Vector3d>& points, std::vector<Eigen::Vector3d>& normals,
             double covered_below) {
  for (double y = -2.0; y <= 2.0; y += 0.02) {
    for (double z = -2.0; z <= 2.0; z += 0.02) {
      if (z < covered_below) continue;
      points.emplace_back(0.0, y, z);
      normals.emplace_back(1.0, 0.0, 0.0);
    }
  }
}

TEST(M3C2, ASurfaceLyingAlongTheCylinderIsNoDisplacement) {
  // A long block fallen against a wall: its top (z = -0.2, normals up) runs out from the wall
  // under the horizontal cylinder of a wall core point at z = 0, and the wall is unchanged
  // there. Lague's M3C2 averages the top's points along the axis into a distance; with the
  // clouds' normals they are not counted and the wall measures no change.
  std::vector<Eigen::Vector3d> before, before_normals, after, after_normals;
  addWall(before, before_normals, -10.0);
  addWall(after, after_normals, -0.2);
  for (double x = 0.02; x <= 1.5; x += 0.02) {
    for (double y = -1.0; y <= 1.0; y += 0.02) {
      after.emplace_back(x, y, -0.2);
      after_normals.emplace_back(0.0, 0.0, 1.0);
    }
  }
  M3C2Options options;
  options.orientation = Eigen::Vector3d::UnitX();
  const std::vector<Eigen::Vector3d> core = {{0.0, 0.0, 0.0}};
  const M3C2Point plain = m3c2(before, after, core, options)[0];
  EXPECT_GT(plain.distance, 0.05) << "the unguarded mean should be pulled out along the top";
  const M3C2Point guarded =
      m3c2({before, nullptr, &before_normals}, {after, nullptr, &after_normals}, core, options)[0];
  ASSERT_TRUE(guarded.valid());
  EXPECT_NEAR(guarded.distance, 0.0, 1e-9);
  EXPECT_LT(guarded.count2, plain.count2);
  // 90 degrees counts every point again.
  options.max_axis_angle_deg = 90.0;
  const M3C2Point all =
      m3c2({before, nullptr, &before_normals}, {after, nullptr, &after_normals}, core, options)[0];
  EXPECT_DOUBLE_EQ(all.distance, plain.distance);
  EXPECT_EQ(all.count2, plain.count2);
}

TEST(M3C2, AChangedSurfaceTiltedAcrossTheCylinderStillCounts) {
  // Growth that leaves a slope: the plane z = 0 becomes z = 0.3 + tan(40°) x. Its normals stand
  // 40° from the axis, within the default 60°: the distance at the core is still 0.3 m.
  const double slope = std::tan(40.0 * kPi / 180.0);
  const auto before = plane(0.0, 0.0, 3);
  const auto after = surface(
      5.0, 0.05, [slope](double x, double) { return 0.3 + slope * x; }, 0.0, 4);
  const std::vector<Eigen::Vector3d> up(before.size(), Eigen::Vector3d::UnitZ());
  const std::vector<Eigen::Vector3d> tilted(after.size(),
                                            Eigen::Vector3d(-slope, 0.0, 1.0).normalized());
  const M3C2Point p =
      m3c2({before, nullptr, &up}, {after, nullptr, &tilted}, {{0, 0, 0}}, upwards())[0];
  ASSERT_TRUE(p.valid());
  EXPECT_NEAR(p.distance, 0.3, 0.02);
  EXPECT_EQ(p.count2, m3c2(before, after, {{0, 0, 0}}, upwards())[0].count2);
  // Normals that do not fit the cloud are refused.
  const std::vector<Eigen::Vector3d> short_normals(up.begin(), up.end() - 1);
  EXPECT_THROW(m3c2({before, nullptr, &short_normals}, {after}, {{0, 0, 0}}, upwards()),
               std::invalid_argument);
}

TEST(M3C2, TooFewPointsGiveNoDistance) {
  const auto before = plane(0.0, 0.0, 9);
  const std::vector<Eigen::Vector3d> sparse = {{0, 0, 0.1}, {0.05, 0, 0.1}};
  const M3C2Point p = m3c2(before, sparse, {{0, 0, 0}}, upwards())[0];
  EXPECT_FALSE(p.valid());
  EXPECT_EQ(p.count2, 2);
  EXPECT_FALSE(p.significant);
  // No neighbours at all: no normal either.
  const M3C2Point far = m3c2(before, sparse, {{50, 50, 0}}, upwards())[0];
  EXPECT_FALSE(far.valid());
  EXPECT_TRUE(far.normal.isZero());
  EXPECT_TRUE(m3c2({}, {}, {{0, 0, 0}}, upwards()).front().normal.isZero());
}

TEST(M3C2, OptionsOutOfRangeAreNamed) {
  M3C2Options options;
  options.projection_scale_m = 0.0;
  try {
    m3c2({}, {}, {}, options);
    FAIL() << "accepted projection_scale_m = 0";
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("projection_scale_m = 0"), std::string::npos) << e.what();
  }
  options = M3C2Options();
  options.min_points = 1;
  EXPECT_THROW(options.check(), OptionError);
  options = M3C2Options();
  options.orientation = Eigen::Vector3d::Zero();
  EXPECT_THROW(options.check(), OptionError);
  for (double angle : {0.0, 90.5}) {
    options = M3C2Options();
    options.max_axis_angle_deg = angle;
    EXPECT_THROW(options.check(), OptionError) << angle;
  }
}

}  // namespace
}  // namespace auv::recon::change
