// What the controller reads from nav/odometry: the fields it acts on, when the velocity counts
// as measured, and an unset orientation.
#include "auv/control/components/odometry_conversion.h"

#include <gtest/gtest.h>

#include <cmath>

#include "auv/interfaces/msg_time.h"

namespace auv::control {
namespace {

// An estimate cruising at 0.6 m/s, heading 2.5 rad, 4 m above the seabed, 12.5 s.
msg::Odometry cruising(uint32_t flags) {
  msg::Odometry odometry;
  odometry.header().stamp(interfaces::toMsgTime(12'500'000'000LL));
  auto& pose = odometry.pose().pose();
  pose.position().x(3.0);
  pose.position().y(-4.0);
  pose.position().z(6.0);
  pose.orientation().z(std::sin(2.5 / 2));
  pose.orientation().w(std::cos(2.5 / 2));
  auto& twist = odometry.twist().twist();
  twist.linear().x(0.6);
  twist.linear().y(0.05);
  twist.linear().z(-0.02);
  twist.angular().z(0.1);
  odometry.altitude(4.0);
  odometry.source_flags(flags);
  return odometry;
}

TEST(OdometryConversion, ControllerReadsTheEstimateItWasSent) {
  bool orientation_ok = false;
  const ControllerNavigation nav = toControllerNavigation(
      cruising(msg::ODOMETRY_SOURCE_DVL_VALID | msg::ODOMETRY_SOURCE_IMU), orientation_ok);
  EXPECT_TRUE(orientation_ok);
  EXPECT_TRUE(nav.position.isApprox(Eigen::Vector3d(3.0, -4.0, 6.0)));
  EXPECT_NEAR(nav.yaw, 2.5, 1e-9);
  EXPECT_DOUBLE_EQ(nav.surge, 0.6);
  EXPECT_DOUBLE_EQ(nav.sway, 0.05);
  EXPECT_DOUBLE_EQ(nav.heave, -0.02);
  EXPECT_DOUBLE_EQ(nav.yaw_rate, 0.1);
  EXPECT_DOUBLE_EQ(nav.altitude, 4.0);
  EXPECT_NEAR(nav.stamp, 12.5, 1e-9);
}

TEST(OdometryConversion, VelocityIsMeasuredOnlyWithDvlLockTruthOrNoFlagsAtAll) {
  bool ok = false;
  const uint32_t dvl = msg::ODOMETRY_SOURCE_DVL_VALID, imu = msg::ODOMETRY_SOURCE_IMU,
                 pressure = msg::ODOMETRY_SOURCE_PRESSURE, gps = msg::ODOMETRY_SOURCE_GPS_FIX,
                 dead_reckoning = msg::ODOMETRY_SOURCE_DEAD_RECKONING;
  EXPECT_TRUE(toControllerNavigation(cruising(dvl | imu | dead_reckoning), ok).velocity_measured);
  // A DVL dropout: the filter holds the velocity.
  EXPECT_FALSE(
      toControllerNavigation(cruising(imu | pressure | dead_reckoning), ok).velocity_measured);
  EXPECT_FALSE(toControllerNavigation(cruising(gps | imu), ok).velocity_measured);
  EXPECT_TRUE(
      toControllerNavigation(cruising(msg::ODOMETRY_SOURCE_GROUND_TRUTH), ok).velocity_measured);
  EXPECT_TRUE(toControllerNavigation(cruising(0), ok).velocity_measured);  // does not fill them
}

TEST(OdometryConversion, UnsetOrientationIsReportedNotTurnedIntoAYaw) {
  msg::Odometry odometry = cruising(msg::ODOMETRY_SOURCE_DVL_VALID);
  odometry.pose().pose().orientation(msg::Quaternion{});
  odometry.pose().pose().orientation().w(0.0);
  bool orientation_ok = true;
  toControllerNavigation(odometry, orientation_ok);
  EXPECT_FALSE(orientation_ok);
}

}  // namespace
}  // namespace auv::control
