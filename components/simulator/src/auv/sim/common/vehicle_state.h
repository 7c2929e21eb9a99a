#pragma once
// The simulated vehicle's true kinematic state. Sparus II is passively stable in roll and pitch,
// so the state is 4-DOF: position (NED), yaw, and body velocities in surge, sway, heave, yaw.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace auv::sim {

struct VehicleState {
  Eigen::Vector3d position{0, 0, 0};  ///< m NED (z = depth)
  double yaw = 0.0;                   ///< rad, 0 = north, +pi/2 = east, in (-pi, pi]
  double surge = 0.0;                 ///< m/s, body x (forward)
  double sway = 0.0;                  ///< m/s, body y (starboard)
  double heave = 0.0;                 ///< m/s, body z (down)
  double yaw_rate = 0.0;              ///< rad/s, about body z

  /// Body FRD -> world NED.
  Eigen::Isometry3d pose() const {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    T.translation() = position;
    return T;
  }
  /// Velocity over ground in NED.
  Eigen::Vector3d velocityWorld() const {
    const double c = std::cos(yaw), s = std::sin(yaw);
    return {c * surge - s * sway, s * surge + c * sway, heave};
  }
};

/// Wraps an angle to (-pi, pi].
inline double wrapAngle(double a) {
  a = std::fmod(a + M_PI, 2.0 * M_PI);
  if (a <= 0) a += 2.0 * M_PI;
  return a - M_PI;
}

}  // namespace auv::sim
