// NavigationJumpDetector: steady motion, turns and long navigation gaps are motion; a reset of
// the estimate by metres is a jump, measured net of the motion predicted from the samples
// before it.
#include <gtest/gtest.h>

#include <stdexcept>

#include "auv/mapping/navigation_jump.h"

namespace auv::mapping {
namespace {

constexpr int64_t kTenHz = 100'000'000;  // ns between samples

TEST(NavigationJumpTest, SteadyMotionAndATurnAreNoJump) {
  NavigationJumpDetector detector({});
  Eigen::Vector3d position(0, 0, 5);
  for (int i = 0; i < 100; ++i) {
    // 1.5 m/s north, then east after 5 s: the turn is a change of velocity, not a jump.
    position += (i < 50 ? Eigen::Vector3d(0.15, 0, 0) : Eigen::Vector3d(0, 0.15, 0));
    EXPECT_FALSE(detector.add(i * kTenHz, position)) << "sample " << i;
  }
}

TEST(NavigationJumpTest, AResetIsAJumpNetOfThePredictedMotion) {
  NavigationJumpDetector detector({});
  Eigen::Vector3d position(0, 0, 5);
  int64_t t = 0;
  for (int i = 0; i < 10; ++i, t += kTenHz) {
    position.x() += 0.1;  // 1 m/s north
    ASSERT_FALSE(detector.add(t, position));
  }
  // The estimate is reset 6.5 m east while the vehicle goes on north.
  position += Eigen::Vector3d(0.1, 6.5, 0);
  const auto jump = detector.add(t, position);
  ASSERT_TRUE(jump);
  EXPECT_NEAR(jump->x(), 0.0, 1e-9);
  EXPECT_NEAR(jump->y(), 6.5, 1e-9);
  EXPECT_NEAR(jump->z(), 0.0, 1e-9);
  // The samples after it are motion again, at the same speed.
  for (int i = 0; i < 10; ++i) {
    t += kTenHz;
    position.x() += 0.1;
    EXPECT_FALSE(detector.add(t, position)) << "sample " << i << " after the jump";
  }
}

TEST(NavigationJumpTest, AStepAfterANavigationGapIsMotionUpToTheTopSpeed) {
  NavigationJumpDetector detector({});  // 1 m threshold, 2.5 m/s
  detector.add(0, {0, 0, 5});
  detector.add(kTenHz, {0, 0, 5});
  // 30 s without navigation: drifting 20 m in that time is possible, 120 m is not.
  EXPECT_FALSE(detector.add(kTenHz + 30'000'000'000, {20, 0, 5}));
  EXPECT_TRUE(detector.add(2 * kTenHz + 60'000'000'000, {140, 0, 5}));
}

TEST(NavigationJumpTest, ZeroThresholdNeverJumpsAndOldStampsAreIgnored) {
  NavigationJumpDetector::Options options;
  options.jump_threshold_m = 0.0;
  NavigationJumpDetector off(options);
  off.add(0, {0, 0, 0});
  EXPECT_FALSE(off.add(kTenHz, {100, 0, 0}));

  NavigationJumpDetector detector({});
  detector.add(kTenHz, {0, 0, 0});
  EXPECT_FALSE(detector.add(0, {50, 0, 0}));  // older: ignored, not a jump
  EXPECT_FALSE(detector.add(2 * kTenHz, {0.1, 0, 0}));
}

TEST(NavigationJumpTest, OptionsOutOfRangeNameTheParameter) {
  NavigationJumpDetector::Options options;
  options.max_speed_mps = 0.0;
  try {
    NavigationJumpDetector detector(options);
    FAIL() << "max_speed 0 accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("max_speed"), std::string::npos) << error.what();
  }
  options = {};
  options.log_odds_scale = 0.0;
  EXPECT_THROW(NavigationJumpDetector{options}, std::invalid_argument);
}

}  // namespace
}  // namespace auv::mapping
