// The simulator's nav/odometry and ground truth read back by the controller's own reader
// (auv_control): the round trip the vehicle stack depends on.
#include "auv/sim/components/message_conversion.h"

#include <gtest/gtest.h>

#include "auv/control/components/odometry_conversion.h"

namespace auv::sim {
namespace {

using control::ControllerNavigation;
using control::toControllerNavigation;

NavigationEstimate cruising(uint32_t flags) {
  NavigationEstimate estimate;
  estimate.stamp = 12.5;
  estimate.position = {3.0, -4.0, 6.0};
  estimate.yaw = 2.5;
  estimate.velocity = {0.6, 0.05, -0.02};
  estimate.altitude = 4.0;
  estimate.source_flags = flags;
  return estimate;
}

TEST(MessageConversion, ControllerReadsTheEstimateItWasSent) {
  bool orientation_ok = false;
  const ControllerNavigation nav = toControllerNavigation(
      toOdometry(cruising(nav_source::kDvlValid | nav_source::kImu)), orientation_ok);
  EXPECT_TRUE(orientation_ok);
  EXPECT_TRUE(nav.position.isApprox(Eigen::Vector3d(3.0, -4.0, 6.0)));
  EXPECT_NEAR(nav.yaw, 2.5, 1e-9);
  EXPECT_DOUBLE_EQ(nav.surge, 0.6);
  EXPECT_DOUBLE_EQ(nav.sway, 0.05);
  EXPECT_DOUBLE_EQ(nav.heave, -0.02);
  EXPECT_DOUBLE_EQ(nav.altitude, 4.0);
  EXPECT_NEAR(nav.stamp, 12.5, 1e-9);
}

TEST(MessageConversion, VelocityIsMeasuredOnlyWithDvlLockTruthOrNoFlagsAtAll) {
  bool ok = false;
  using namespace nav_source;
  EXPECT_TRUE(toControllerNavigation(toOdometry(cruising(kDvlValid | kImu | kDeadReckoning)), ok)
                  .velocity_measured);
  // A DVL dropout: the filter holds the velocity.
  EXPECT_FALSE(toControllerNavigation(toOdometry(cruising(kImu | kPressure | kDeadReckoning)), ok)
                   .velocity_measured);
  EXPECT_FALSE(toControllerNavigation(toOdometry(cruising(kGpsFix | kImu)), ok).velocity_measured);
  EXPECT_TRUE(
      toControllerNavigation(groundTruthOdometry(VehicleState{}, 1.0, 5.0), ok).velocity_measured);
  msg::Odometry unflagged = toOdometry(cruising(kImu));
  unflagged.source_flags(0);  // a source that does not fill them
  EXPECT_TRUE(toControllerNavigation(unflagged, ok).velocity_measured);
}

}  // namespace
}  // namespace auv::sim
