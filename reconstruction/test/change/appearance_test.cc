// Appearance change: a bleached patch on a seabed filmed in other light is found, the light's
// difference (gain and offset) is taken out, and places whose shape changed are left alone.
#include "auv/recon/change/appearance.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>

#include "auv/recon/common/stage_error.h"

namespace auv::recon::change {
namespace {

struct Cloud {
  std::vector<Eigen::Vector3d> points, colors;
};

/// A 10 x 10 m seabed at 1 cm spacing jitter, colour varying across it (rock and sand).
Cloud seabed(uint32_t seed, const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& paint) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> jitter(-0.01, 0.01);
  std::normal_distribution<double> noise(0.0, 0.01);
  Cloud cloud;
  for (double x = 0.0; x < 10.0; x += 0.04) {
    for (double y = 0.0; y < 10.0; y += 0.04) {
      const Eigen::Vector3d p(x + jitter(random), y + jitter(random), 8.0);
      cloud.points.push_back(p);
      Eigen::Vector3d c = paint(p) + Eigen::Vector3d(noise(random), noise(random), noise(random));
      cloud.colors.push_back(c.cwiseMax(0.0).cwiseMin(1.0));
    }
  }
  return cloud;
}

Eigen::Vector3d ground(const Eigen::Vector3d& p) {
  return {0.35 + 0.1 * std::sin(p.x()), 0.40 + 0.1 * std::cos(0.7 * p.y()),
          0.30 + 0.08 * std::sin(0.5 * (p.x() + p.y()))};
}

std::vector<Eigen::Vector3d> cores() {
  std::vector<Eigen::Vector3d> c;
  for (double x = 0.1; x < 10.0; x += 0.2)
    for (double y = 0.1; y < 10.0; y += 0.2) c.emplace_back(x, y, 8.0);
  return c;
}

bool inPatch(const Eigen::Vector3d& p) {
  return (p.head<2>() - Eigen::Vector2d(3, 3)).norm() < 1.0;
}

TEST(AppearanceTest, LabOfKnownColours) {
  EXPECT_NEAR(srgbToLab({1, 1, 1}).x(), 100.0, 0.05);
  EXPECT_NEAR(srgbToLab({1, 1, 1}).tail<2>().norm(), 0.0, 0.05);
  const Eigen::Vector3d red = srgbToLab({1, 0, 0});  // CIE: L 53.24, a 80.09, b 67.20
  EXPECT_NEAR(red.x(), 53.24, 0.1);
  EXPECT_NEAR(red.y(), 80.09, 0.2);
  EXPECT_NEAR(red.z(), 67.20, 0.2);
}

TEST(AppearanceTest, FindsTheBleachedPatchThroughOtherLightAndSkipsChangedShape) {
  const Cloud before = seabed(1, ground);
  // The later visit: brighter, bluer light (gain and offset per channel), and a bleached patch.
  const Cloud after = seabed(2, [](const Eigen::Vector3d& p) {
    Eigen::Vector3d c = inPatch(p) ? Eigen::Vector3d(0.85, 0.85, 0.8) : ground(p);
    return Eigen::Vector3d(1.2 * c.x() + 0.02, 1.1 * c.y(), 0.9 * c.z() + 0.08);
  });
  const std::vector<Eigen::Vector3d> core = cores();
  // A place whose shape changed elsewhere: excluded even though its colour is the same.
  std::vector<char> exclude(core.size(), 0);
  for (size_t i = 0; i < core.size(); ++i)
    exclude[i] = (core[i].head<2>() - Eigen::Vector2d(7, 7)).norm() < 0.5;
  const AppearanceResult r = compareAppearance(before.points, before.colors, after.points,
                                               after.colors, core, exclude, {});
  EXPECT_NEAR(r.gain.x(), 1.0 / 1.2, 0.03);
  EXPECT_NEAR(r.offset.z(), -0.08 / 0.9, 0.02);
  size_t patch = 0, found = 0, false_alarms = 0;
  for (size_t i = 0; i < core.size(); ++i) {
    if (exclude[i]) {
      EXPECT_FALSE(r.significant[i]);
      EXPECT_TRUE(std::isnan(r.delta_e[i]));
      continue;
    }
    const bool inside = (core[i].head<2>() - Eigen::Vector2d(3, 3)).norm() < 0.9;
    // Colours are averaged within 0.2 m: the patch shows up to 1.2 m from its centre.
    const bool outside = (core[i].head<2>() - Eigen::Vector2d(3, 3)).norm() > 1.25;
    patch += inside;
    found += inside && r.significant[i];
    false_alarms += outside && r.significant[i];
  }
  EXPECT_GT(patch, 50u);
  EXPECT_EQ(found, patch);
  EXPECT_EQ(false_alarms, 0u);
  EXPECT_LT(r.median_delta_e, 3.0);  // the light's difference is taken out
  EXPECT_EQ(r.measured + std::count(exclude.begin(), exclude.end(), 1), core.size());
  const std::vector<AppearanceCluster> clusters = clusterAppearance(core, r, 0.2, 0.3, 0.05);
  ASSERT_EQ(clusters.size(), 1u);
  // The 1 m disc, core points 0.2 m apart, colours averaged within 0.2 m of them.
  EXPECT_GT(clusters[0].area_m2, M_PI * 0.9 * 0.9);
  EXPECT_LT(clusters[0].area_m2, M_PI * 1.25 * 1.25);
  EXPECT_NEAR(clusters[0].centroid.x(), 3.0, 0.05);
  EXPECT_GT(clusters[0].mean_delta_e, r.threshold);
}

TEST(AppearanceTest, AChannelThatHardlyVariesGetsAnOffsetNotAGain) {
  const auto flat_blue = [](const Eigen::Vector3d& p) {
    return Eigen::Vector3d(ground(p).x(), ground(p).y(), 0.30);
  };
  const Cloud before = seabed(1, flat_blue);
  const Cloud after = seabed(2, [&](const Eigen::Vector3d& p) {
    return Eigen::Vector3d(flat_blue(p).x(), flat_blue(p).y(), inPatch(p) ? 0.9 : 0.25);
  });
  const AppearanceResult r =
      compareAppearance(before.points, before.colors, after.points, after.colors, cores(), {}, {});
  EXPECT_NEAR(r.gain.z(), 1.0, 1e-12);
  EXPECT_NEAR(r.offset.z(), 0.05, 0.01);
  EXPECT_GT(r.significant_count, 50u);  // the blue patch is not normalised away
}

TEST(AppearanceTest, BadOptionsAreNamed) {
  AppearanceOptions options;
  options.radius_m = 0.0;
  try {
    options.check();
    FAIL() << "radius 0 accepted";
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("radius_m"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace auv::recon::change
