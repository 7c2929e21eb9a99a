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

// Pearson correlation of the log-factors at points and the same points moved by `shift`.
double shiftedCorrelation(const SurfaceDetail& detail, const Eigen::Vector3f& shift) {
  const Eigen::Vector3f n(0, 0, 1);
  std::vector<double> a, b;
  for (int i = 0; i < 400; ++i) {
    const Eigen::Vector3f p(0.0137f * i, 0.0071f * (i % 37), 0);
    a.push_back(std::log(detail.factor(p, n)));
    b.push_back(std::log(detail.factor(p + shift, n)));
  }
  auto mean = [](const std::vector<double>& v) {
    double s = 0;
    for (double x : v) s += x;
    return s / v.size();
  };
  const double ma = mean(a), mb = mean(b);
  double sab = 0, saa = 0, sbb = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  return sab / std::sqrt(saa * sbb);
}

// Plain sand shows nothing but the detail: a pattern repeating every tile made image matching
// find the same patch one tile away (the canyon survey registered 16 of 55 keyframes).
TEST(SurfaceDetailTest, DoesNotRepeatAtTheTileSizeOrItsMultiples) {
  const SurfaceDetail detail(options(0.8, 1));  // tile 0.5 m
  EXPECT_GT(shiftedCorrelation(detail, {0.001f, 0, 0}), 0.9);  // the measure sees likeness
  for (float shift : {0.5f, 1.0f, 0.809017f, 1.618034f, 4.0f, 6.5f, 10.0f}) {
    EXPECT_LT(std::abs(shiftedCorrelation(detail, {shift, 0, 0})), 0.6) << shift;
    EXPECT_LT(std::abs(shiftedCorrelation(detail, {0, shift, 0})), 0.6) << shift;
  }
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
