// Surface detail: a fixed pattern in world coordinates (every view agrees), mean factor 1,
// seeded, and continuous across tile edges.
#include "auv/sim/world/surface_detail.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "auv/sim/common/yaml_section.h"

namespace auv::sim {
namespace {

SurfaceDetailOptions options(double amplitude, int64_t seed) {
  SurfaceDetailOptions o;
  o.amplitude = amplitude;
  o.seed = seed;
  return o;
}

TEST(SurfaceDetailTest, FactorsAverageOneWithTheRequestedLogSpread) {
  const SurfaceDetail detail(options(0.5, 3));
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-20, 20);
  double sum = 0, sum_log = 0, sum_log2 = 0;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    const float f = detail.factor({u(rng), u(rng), u(rng)}, {0, 0, -1});  // a floor
    ASSERT_GT(f, 0.0f);
    sum += f;
    sum_log += std::log(f);
    sum_log2 += std::log(f) * std::log(f);
  }
  const double mean_log = sum_log / n;
  EXPECT_NEAR(sum / n, 1.0, 0.05);
  // A single projection (floor) keeps the full spread of the normalised tile.
  EXPECT_NEAR(std::sqrt(sum_log2 / n - mean_log * mean_log), 0.5, 0.05);
}

TEST(SurfaceDetailTest, SamePointSameFactorAndSeedsDiffer) {
  const SurfaceDetail a(options(0.8, 1)), again(options(0.8, 1)), other(options(0.8, 2));
  const Eigen::Vector3f p(1.234f, -5.6f, 3.3f), n = Eigen::Vector3f(1, 1, 0).normalized();
  EXPECT_EQ(a.factor(p, n), again.factor(p, n));
  EXPECT_EQ(a.factor(p, n), a.factor(p, -n));  // seen from either side
  EXPECT_NE(a.factor(p, n), other.factor(p, n));
}

TEST(SurfaceDetailTest, ContinuousAcrossTileEdgesAndVaryingWithinATile) {
  const SurfaceDetail detail(options(0.8, 5));  // tile 0.5 m
  const Eigen::Vector3f n(0, 0, 1);
  const float eps = 2e-6f;  // 0.002 texel: far below the finest octave (2 texels)
  for (float edge : {0.5f, 1.0f, -0.5f}) {
    const float before = detail.factor({edge - eps, 0.2f, 0}, n);
    const float after = detail.factor({edge + eps, 0.2f, 0}, n);
    EXPECT_NEAR(before, after, 0.01f * before) << edge;
  }
  // Fine scale: points a centimetre apart differ noticeably somewhere.
  float largest = 0;
  for (int i = 0; i < 100; ++i) {
    const float x = 0.005f * i;
    largest = std::max(largest, std::abs(std::log(detail.factor({x, 0, 0}, n)) -
                                         std::log(detail.factor({x + 0.01f, 0, 0}, n))));
  }
  EXPECT_GT(largest, 0.2f);
}

TEST(SurfaceDetailTest, BadOptionsNameTheField) {
  SurfaceDetailOptions o;
  o.tile_size = 0;
  try {
    o.check("world.surface_detail");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("world.surface_detail.tile_size"), std::string::npos);
  }
}

}  // namespace
}  // namespace auv::sim
