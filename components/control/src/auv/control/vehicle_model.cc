#include "auv/control/vehicle_model.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace auv::control {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

double drag(double v, double linear, double quadratic) {
  return linear * v + quadratic * std::abs(v) * v;
}

// One semi-implicit Euler step of (mass) dv/dt = force - linear v - quadratic |v| v: the drag
// is taken at the new velocity, linearised about the old one, so the step is stable for any dt
// and its fixed point is exactly the terminal speed of the drag model.
double integrateVelocity(double v, double force, double mass, double linear, double quadratic,
                         double dt) {
  return (mass * v + dt * force) / (mass + dt * (linear + quadratic * std::abs(v)));
}

}  // namespace

const config::OptionTable<VehicleModel>& VehicleModel::table() {
  using config::Range;
  using V = VehicleModel;
  const Range positive = Range::above(0.0), non_negative = Range::atLeast(0.0);
  static const config::OptionTable<V> kTable = {
      {"length", &V::length, "hull length (collision checks)", "m", Range::aboveUpTo(0, 100)},
      {"radius", &V::radius, "hull radius (collision checks)", "m", Range::aboveUpTo(0, 10)},
      {"mass", &V::mass, "rigid-body mass", "kg", positive},
      {"yaw_inertia", &V::yaw_inertia, "rigid-body moment of inertia about body z", "kg m^2",
       positive},
      {"added_mass_surge", &V::added_mass_surge, "added mass in surge", "kg", non_negative},
      {"added_mass_sway", &V::added_mass_sway, "added mass in sway", "kg", non_negative},
      {"added_mass_heave", &V::added_mass_heave, "added mass in heave", "kg", non_negative},
      {"added_inertia_yaw", &V::added_inertia_yaw, "added inertia in yaw", "kg m^2", non_negative},
      {"drag_linear_surge", &V::drag_linear_surge, "linear surge drag", "N/(m/s)", non_negative},
      {"drag_quadratic_surge", &V::drag_quadratic_surge, "quadratic surge drag", "N/(m/s)^2",
       non_negative},
      {"drag_linear_sway", &V::drag_linear_sway, "linear sway drag", "N/(m/s)", non_negative},
      {"drag_quadratic_sway", &V::drag_quadratic_sway, "quadratic sway drag", "N/(m/s)^2",
       non_negative},
      {"drag_linear_heave", &V::drag_linear_heave, "linear heave drag", "N/(m/s)", non_negative},
      {"drag_quadratic_heave", &V::drag_quadratic_heave, "quadratic heave drag", "N/(m/s)^2",
       non_negative},
      {"drag_linear_yaw", &V::drag_linear_yaw, "linear yaw drag", "N m/(rad/s)", non_negative},
      {"drag_quadratic_yaw", &V::drag_quadratic_yaw, "quadratic yaw drag", "N m/(rad/s)^2",
       non_negative},
      {"max_thrust_forward", &V::max_thrust_forward, "thrust of one thruster at +1", "N", positive},
      {"max_thrust_reverse", &V::max_thrust_reverse, "thrust of one thruster at -1", "N", positive},
      {"thruster_time_constant", &V::thruster_time_constant,
       "first-order thrust response; 0 = instantaneous", "s", Range::closed(0, 60)},
      {"thruster_spacing", &V::thruster_spacing,
       "lateral distance between the horizontal thrusters", "m", Range::aboveUpTo(0, 10)},
      {"net_buoyancy", &V::net_buoyancy, "buoyancy minus weight (> 0 floats)", "N", Range::any()},
      {"max_surge_speed", &V::max_surge_speed, "hard limit of |surge|", "m/s", positive},
      {"max_sway_speed", &V::max_sway_speed, "hard limit of |sway|", "m/s", positive},
      {"max_heave_speed", &V::max_heave_speed, "hard limit of |heave|", "m/s", positive},
      {"max_yaw_rate", &V::max_yaw_rate, "hard limit of |yaw rate|", "rad/s", positive},
  };
  return kTable;
}

void VehicleModel::check() const {
  config::checkOptions<ConfigError>(*this, table(), "vehicle.");
  const struct {
    const char* dof;
    double linear, quadratic;
  } drags[] = {{"surge", drag_linear_surge, drag_quadratic_surge},
               {"sway", drag_linear_sway, drag_quadratic_sway},
               {"heave", drag_linear_heave, drag_quadratic_heave},
               {"yaw", drag_linear_yaw, drag_quadratic_yaw}};
  for (const auto& d : drags) {
    // Without any drag the speed would grow without bound under constant thrust.
    if (d.linear + d.quadratic <= 0) {
      throw ConfigError(std::string("vehicle.drag_linear_") + d.dof + ": drag_linear_" + d.dof +
                        " and drag_quadratic_" + d.dof + " are both 0; at least one must be > 0");
    }
  }
}

double VehicleModel::thrustForCommand(double command) const {
  const double c = std::clamp(command, -1.0, 1.0);
  return c >= 0 ? c * max_thrust_forward : c * max_thrust_reverse;
}

double VehicleModel::commandForThrust(double thrust) const {
  const double c = thrust >= 0 ? thrust / max_thrust_forward : thrust / max_thrust_reverse;
  return std::clamp(c, -1.0, 1.0);
}

double VehicleModel::surgeDrag(double speed) const {
  return drag(speed, drag_linear_surge, drag_quadratic_surge);
}

double VehicleModel::heaveDrag(double speed) const {
  return drag(speed, drag_linear_heave, drag_quadratic_heave);
}

double VehicleModel::yawDrag(double rate) const {
  return drag(rate, drag_linear_yaw, drag_quadratic_yaw);
}

double VehicleModel::maxYawMoment() const {
  // One thruster at full forward, the other at full reverse.
  return 0.5 * thruster_spacing * (max_thrust_forward + max_thrust_reverse);
}

double terminalSpeed(double force, double linear, double quadratic) {
  const double f = std::abs(force);
  double v = 0;
  if (quadratic > 0) {
    v = (-linear + std::sqrt(linear * linear + 4.0 * quadratic * f)) / (2.0 * quadratic);
  } else if (linear > 0) {
    v = f / linear;
  } else {
    v = f > 0 ? kInf : 0.0;
  }
  return force >= 0 ? v : -v;
}

VehicleDynamics::VehicleDynamics(const VehicleModel& options) : options_(options) {
  options_.check();
}

void VehicleDynamics::setThrust(const ThrusterCommand& command) {
  thrust_ = {options_.thrustForCommand(command.port), options_.thrustForCommand(command.starboard),
             options_.thrustForCommand(command.vertical)};
}

void VehicleDynamics::step(VehicleState& state, const ThrusterCommand& command, double dt) {
  if (!std::isfinite(dt) || dt < 0) {
    throw std::invalid_argument("VehicleDynamics::step: dt must be finite and >= 0, got " +
                                std::to_string(dt));
  }
  // NaN commands count as 0: a broken setpoint must not poison the state.
  auto sanitize = [](double c) { return std::isfinite(c) ? c : 0.0; };
  const std::array<double, 3> target = {options_.thrustForCommand(sanitize(command.port)),
                                        options_.thrustForCommand(sanitize(command.starboard)),
                                        options_.thrustForCommand(sanitize(command.vertical))};
  const int substeps = std::max(1, static_cast<int>(std::ceil(dt / kMaxSubstep - 1e-9)));
  const double h = dt / substeps;
  for (int i = 0; i < substeps; ++i) substep(state, target, h);
}

void VehicleDynamics::substep(VehicleState& state, const std::array<double, 3>& target_thrust,
                              double dt) {
  const VehicleModel& o = options_;
  // First-order thruster response, exact for a command held over the step.
  const double blend =
      o.thruster_time_constant > 0 ? 1.0 - std::exp(-dt / o.thruster_time_constant) : 1.0;
  for (size_t i = 0; i < 3; ++i) thrust_[i] += (target_thrust[i] - thrust_[i]) * blend;

  const double port = thrust_[0], starboard = thrust_[1], vertical = thrust_[2];
  const double surge_force = port + starboard + o.mass * state.yaw_rate * state.sway;
  const double sway_force = -o.mass * state.yaw_rate * state.surge;
  // Net buoyancy pushes up, i.e. towards negative z in NED.
  const double heave_force = vertical - o.net_buoyancy;
  // The port thruster sits at y = -spacing/2: pushing forward it turns the bow to starboard
  // (positive yaw about body z, down).
  const double yaw_moment = 0.5 * o.thruster_spacing * (port - starboard);

  state.surge = integrateVelocity(state.surge, surge_force, o.surgeMass(), o.drag_linear_surge,
                                  o.drag_quadratic_surge, dt);
  state.sway = integrateVelocity(state.sway, sway_force, o.swayMass(), o.drag_linear_sway,
                                 o.drag_quadratic_sway, dt);
  state.heave = integrateVelocity(state.heave, heave_force, o.heaveMass(), o.drag_linear_heave,
                                  o.drag_quadratic_heave, dt);
  state.yaw_rate = integrateVelocity(state.yaw_rate, yaw_moment, o.yawInertia(), o.drag_linear_yaw,
                                     o.drag_quadratic_yaw, dt);

  state.surge = std::clamp(state.surge, -o.max_surge_speed, o.max_surge_speed);
  state.sway = std::clamp(state.sway, -o.max_sway_speed, o.max_sway_speed);
  state.heave = std::clamp(state.heave, -o.max_heave_speed, o.max_heave_speed);
  state.yaw_rate = std::clamp(state.yaw_rate, -o.max_yaw_rate, o.max_yaw_rate);

  // Kinematics with the new velocities (semi-implicit Euler).
  state.position += state.velocityWorld() * dt;
  state.yaw += state.yaw_rate * dt;
  if (state.yaw > M_PI || state.yaw <= -M_PI) state.yaw = wrapAngle(state.yaw);  // else exact

  // The surface: the hull floats there, it cannot rise further.
  if (state.position.z() < 0) {
    state.position.z() = 0;
    state.heave = std::max(state.heave, 0.0);
  }
}

}  // namespace auv::control
