// The local bias of two surveys: a smooth bend between the two models (what two
// reconstructions on their own drifting navigation differ by) is taken out, a block smaller
// than the neighbourhood is kept whole, and the level of detection follows the residual.
#include "auv/recon/change/local_bias.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace auv::recon::change {
namespace {

struct Site {
  std::vector<Eigen::Vector3d> cores;
  std::vector<M3C2Point> comparison;
};

/// Core points 0.2 m apart on 20 x 20 m; distances: a bend of +-6 cm over ~20 m, 5 mm noise,
/// and `block_height` on x, y in (2, 2 + block_side).
Site site(double block_height, double block_side) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.005);
  Site s;
  for (double x = -10.0; x < 10.0; x += 0.2) {
    for (double y = -10.0; y < 10.0; y += 0.2) {
      s.cores.emplace_back(x, y, 20.0);
      M3C2Point p;
      p.distance = 0.06 * std::sin(x / 6.0) + 0.03 * std::cos(y / 8.0) + noise(rng);
      if (x > 2.0 && x < 2.0 + block_side && y > 2.0 && y < 2.0 + block_side)
        p.distance += block_height;
      p.spread1 = p.spread2 = 0.01;
      p.count1 = p.count2 = 20;
      s.comparison.push_back(p);
    }
  }
  return s;
}

bool onBlock(const Eigen::Vector3d& c, double side, double margin) {
  return c.x() > 2.0 + margin && c.x() < 2.0 + side - margin && c.y() > 2.0 + margin &&
         c.y() < 2.0 + side - margin;
}

TEST(LocalBias, TakesOutTheBendAndKeepsTheBlock) {
  Site s = site(0.3, 2.0);
  applyLevelOfDetection(s.comparison, 0.01, 1.96);
  size_t false_before = 0;
  for (size_t i = 0; i < s.cores.size(); ++i)
    false_before += !onBlock(s.cores[i], 2.0, -0.3) && s.comparison[i].significant;
  EXPECT_GT(false_before, s.cores.size() / 2) << "the bend reads as change without the bias";

  const LocalBias bias = removeLocalBias(s.cores, s.comparison, 4.0);
  EXPECT_LT(bias.residual_sigma_m, 0.01);
  EXPECT_GT(bias.median_abs_bias_m, 0.02);
  applyLevelOfDetection(s.comparison, bias.residual_sigma_m, 1.96);
  size_t on_block = 0, found = 0, off_block = 0, false_after = 0;
  for (size_t i = 0; i < s.cores.size(); ++i) {
    if (onBlock(s.cores[i], 2.0, 0.0)) {
      ++on_block;
      found += s.comparison[i].significant;
      EXPECT_NEAR(s.comparison[i].distance, 0.3, 0.03);
    } else if (!onBlock(s.cores[i], 2.0, -0.3)) {
      ++off_block;
      false_after += s.comparison[i].significant;
    }
  }
  EXPECT_EQ(found, on_block);
  EXPECT_LT(static_cast<double>(false_after), 0.01 * static_cast<double>(off_block));
}

TEST(LocalBias, AChangeWiderThanHalfTheNeighbourhoodIsAbsorbed) {
  // The documented limit: a 9 x 9 m rise under a 4 m radius is mostly taken for the bend.
  Site s = site(0.3, 9.0);
  removeLocalBias(s.cores, s.comparison, 4.0);
  size_t centre = 0, kept = 0;
  for (size_t i = 0; i < s.cores.size(); ++i) {
    if (!onBlock(s.cores[i], 9.0, 3.0)) continue;
    ++centre;
    kept += std::abs(s.comparison[i].distance) > 0.15;
  }
  EXPECT_GT(centre, 100u);
  EXPECT_LT(kept, centre / 10);
}

TEST(LocalBias, UnmeasuredPointsAndSparseNeighbourhoodsAreLeftAlone) {
  Site s = site(0.0, 0.0);
  s.comparison[0].distance = std::numeric_limits<double>::quiet_NaN();
  const double far_before = s.comparison[5].distance;
  const LocalBias bias = removeLocalBias(s.cores, s.comparison, 0.3, 1000);
  EXPECT_TRUE(std::isnan(s.comparison[0].distance));
  EXPECT_EQ(bias.bias[5], 0.0);
  EXPECT_EQ(s.comparison[5].distance, far_before);
}

}  // namespace
}  // namespace auv::recon::change
