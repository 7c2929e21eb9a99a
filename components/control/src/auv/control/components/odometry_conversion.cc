#include "auv/control/components/odometry_conversion.h"

#include <cmath>

#include <Eigen/Geometry>

#include "auv/interfaces/msg_time.h"

namespace auv::control {

ControllerNavigation toControllerNavigation(const msg::Odometry& odometry, bool& orientation_ok) {
  const auto& pose = odometry.pose().pose();
  const auto& q = pose.orientation();
  const auto& twist = odometry.twist().twist();
  ControllerNavigation nav;
  nav.position = {pose.position().x(), pose.position().y(), pose.position().z()};
  // Yaw of the body -> world rotation (ZYX Euler).
  nav.yaw = std::atan2(2.0 * (q.w() * q.z() + q.x() * q.y()),
                       1.0 - 2.0 * (q.y() * q.y() + q.z() * q.z()));
  nav.surge = twist.linear().x();
  nav.sway = twist.linear().y();
  nav.heave = twist.linear().z();
  nav.yaw_rate = twist.angular().z();
  nav.altitude = odometry.altitude();
  nav.stamp = interfaces::toNanoseconds(odometry.header().stamp()) * 1e-9;
  const uint32_t flags = odometry.source_flags();
  nav.velocity_measured =
      flags == 0 ||
      (flags & (msg::ODOMETRY_SOURCE_DVL_VALID | msg::ODOMETRY_SOURCE_GROUND_TRUTH)) != 0;
  const double norm = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z()).coeffs().norm();
  orientation_ok = std::isfinite(norm) && std::abs(norm - 1.0) < 0.1;
  return nav;
}

}  // namespace auv::control
