#pragma once
// The vehicle model shared by the controller (feed-forward, allocation) and the simulator
// (integration): state, thruster setpoints, physical parameters and the dynamics.
//
// Sparus II-like vehicle dynamics: a torpedo actuated in surge, heave and yaw by three thrusters
// (port and starboard horizontal, one vertical), passively stable in roll and pitch (4-DOF).
//
// The marine-craft model M dv/dt + C(v) v + D(v) v = tau (Fossen, "Handbook of Marine Craft
// Hydrodynamics and Motion Control", 2011) reduced to diagonal mass and damping, per DOF:
//   (m + m_a) dv/dt = tau + coriolis - d_lin v - d_quad |v| v
// with the rigid-body Coriolis terms of the horizontal plane (m r v in surge, -m r u in sway),
// which exchange energy between surge and sway without creating any. The hydrodynamic Munk
// moment is left out: on the real vehicle the tail fins cancel most of it.

#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "auv/config/errors.h"
#include "auv/config/option_table.h"

namespace auv::control {

/// An option or model value is unusable; the message names the field ("vehicle.mass: ...").
using config::ConfigError;

/// The vehicle's kinematic state. Sparus II is passively stable in roll and pitch, so the state
/// is 4-DOF: position (NED), yaw, and body velocities in surge, sway, heave, yaw.
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

/// Normalised thruster setpoints, each in [-1, 1] (values outside are clamped). + pushes the
/// vehicle forward (port, starboard) or down, i.e. deeper (vertical); as ThrusterSetpoints.
struct ThrusterCommand {
  double port = 0.0;
  double starboard = 0.0;
  double vertical = 0.0;
};

/// Physical parameters of the vehicle: the simulator integrates them (its scenario section
/// `vehicle:`), the controller uses them for feed-forward and thrust allocation. Defaults model a
/// Sparus II: full forward thrust gives ~1.2 m/s, cruise 0.5-1 m/s needs 20-70 % thrust, the
/// full differential turns at ~0.5 rad/s, and with thrusters off it rises at ~5 cm/s.
struct VehicleModel {
  // Body.
  double length = 1.6;        ///< m, hull length (collision checks)
  double radius = 0.115;      ///< m, hull radius (collision checks)
  double mass = 52.0;         ///< kg, rigid-body mass
  double yaw_inertia = 11.3;  ///< kg m^2, rigid-body moment of inertia about body z

  // Added mass (the water accelerated with the hull).
  double added_mass_surge = 5.0;   ///< kg
  double added_mass_sway = 40.0;   ///< kg
  double added_mass_heave = 50.0;  ///< kg
  double added_inertia_yaw = 6.0;  ///< kg m^2

  // Drag: force = linear * v + quadratic * |v| v.
  double drag_linear_surge = 5.0;       ///< N/(m/s)
  double drag_quadratic_surge = 30.0;   ///< N/(m/s)^2
  double drag_linear_sway = 60.0;       ///< N/(m/s)
  double drag_quadratic_sway = 300.0;   ///< N/(m/s)^2
  double drag_linear_heave = 30.0;      ///< N/(m/s)
  double drag_quadratic_heave = 200.0;  ///< N/(m/s)^2
  double drag_linear_yaw = 4.0;         ///< N m/(rad/s)
  double drag_quadratic_yaw = 24.0;     ///< N m/(rad/s)^2

  // Thrusters (all three alike). Thrust is linear in the normalised command.
  double max_thrust_forward = 25.0;     ///< N, thrust of one thruster at +1
  double max_thrust_reverse = 15.0;     ///< N, thrust magnitude of one thruster at -1
  double thruster_time_constant = 0.2;  ///< s, first-order thrust response; 0 = instantaneous
  double thruster_spacing = 0.4;        ///< m, lateral distance between the horizontal thrusters

  /// N, buoyancy minus weight; > 0 makes the vehicle rise slowly with the thrusters off.
  double net_buoyancy = 2.0;

  // Hard limits applied after each step (above the speeds the thrusters can reach).
  double max_surge_speed = 1.5;  ///< m/s, |surge|
  double max_sway_speed = 0.5;   ///< m/s, |sway|
  double max_heave_speed = 0.6;  ///< m/s, |heave|
  double max_yaw_rate = 0.6;     ///< rad/s, |yaw rate|

  /// Every field with meaning, unit and range, declared once: check(), the simulator's
  /// scenario reader and the controller's `controller.model.*` parameters use it.
  static const config::OptionTable<VehicleModel>& table();

  /// Throws ConfigError naming the field ("vehicle.<name>") when a value is non-finite or out
  /// of range.
  void check() const;

  double surgeMass() const { return mass + added_mass_surge; }           ///< kg
  double swayMass() const { return mass + added_mass_sway; }             ///< kg
  double heaveMass() const { return mass + added_mass_heave; }           ///< kg
  double yawInertia() const { return yaw_inertia + added_inertia_yaw; }  ///< kg m^2

  /// N, thrust of one thruster for a normalised command (clamped to [-1, 1]).
  double thrustForCommand(double command) const;
  /// Normalised command (in [-1, 1]) giving `thrust` N from one thruster, saturated.
  double commandForThrust(double thrust) const;
  /// N, surge drag at `speed` m/s (the thrust needed to keep that speed).
  double surgeDrag(double speed) const;
  /// N, heave drag at `speed` m/s.
  double heaveDrag(double speed) const;
  /// N m, yaw drag at `rate` rad/s.
  double yawDrag(double rate) const;
  /// N m, the largest yaw moment the horizontal pair can produce (full differential).
  double maxYawMoment() const;
};

/// Speed at which linear + quadratic drag balances a constant `force` (sign follows the
/// force): the positive root of quadratic v^2 + linear v = |force|.
double terminalSpeed(double force, double linear, double quadratic);

/// Integrates the vehicle's motion under thruster commands. Keeps the thrusters' actual thrust
/// (the first-order response) between steps. The surface is a hard limit: depth never < 0.
class VehicleDynamics {
 public:
  /// Throws ConfigError if the options do not pass check().
  explicit VehicleDynamics(const VehicleModel& options);

  /// Advances `state` by `dt` s (>= 0; any size, sub-stepped internally at <= kMaxSubstep)
  /// holding `command` constant. Throws std::invalid_argument for negative or non-finite dt.
  void step(VehicleState& state, const ThrusterCommand& command, double dt);

  /// N, actual thrust of the port, starboard and vertical thrusters.
  const std::array<double, 3>& thrust() const { return thrust_; }
  /// Sets the actual thrust at once, e.g. to start a test at steady state.
  void setThrust(const ThrusterCommand& command);
  /// Thrusters back to zero thrust.
  void reset() { thrust_ = {0.0, 0.0, 0.0}; }
  const VehicleModel& options() const { return options_; }

  /// s, longest internal integration step (semi-implicit Euler, stable for any dt).
  static constexpr double kMaxSubstep = 0.01;

 private:
  void substep(VehicleState& state, const std::array<double, 3>& target_thrust, double dt);

  VehicleModel options_;
  std::array<double, 3> thrust_{0.0, 0.0, 0.0};  // N: port, starboard, vertical
};

}  // namespace auv::control
