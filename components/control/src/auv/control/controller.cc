#include "auv/control/controller.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

namespace auv::control {
namespace {

// Integrals only accumulate close to the setpoint and nearly at rest there (conditional
// integration): they are for steady model errors, and integrating during the approach would
// only add overshoot.
constexpr double kHeadingIntegralBand = 0.1;    // rad
constexpr double kYawRateIntegralBand = 0.03;   // rad/s
constexpr double kDepthIntegralBand = 0.25;     // m
constexpr double kHeaveIntegralBand = 0.03;     // m/s
constexpr double kDepthRateTimeConstant = 0.3;  // s, low-pass of the depth's own rate
// m, how far ahead along a leg its depth is taken: the depth loop lags a ramp by ~2-3 s at
// cruise speed, so the target leads by about that much and the vehicle stays on the leg.
constexpr double kLegDepthLead = 2.0;
constexpr double kSurgeIntegralBand = 0.05;  // m/s
// Longest step the integrals take, so a stalled caller does not jolt them.
constexpr double kMaxControlStep = 0.2;  // s

std::string number(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

double clampIntegral(double integral, double gain, double limit) {
  if (gain <= 0) return 0.0;
  const double bound = limit / gain;
  return std::clamp(integral, -bound, bound);
}

template <size_t N, class Enum>
const char* nameOf(const char* const (&names)[N], Enum value) {
  const auto index = static_cast<size_t>(value);
  return index < N ? names[index] : "UNKNOWN_VALUE";
}

}  // namespace

const char* toString(ControlMode mode) {
  static const char* const kNames[] = {"NONE", "STOP", "HOLD", "WAYPOINT", "SETPOINT", "SURFACE"};
  return nameOf(kNames, mode);
}

const char* toString(ControllerState state) {
  static const char* const kNames[] = {"UNKNOWN",         "IDLE", "ACTIVE", "HOLDING",
                                       "SAFETY_MANEUVER", "FAULT"};
  return nameOf(kNames, state);
}

const char* toString(SafetyReason reason) {
  static const char* const kNames[] = {
      "NONE",        "MIN_ALTITUDE", "MAX_DEPTH",       "OBSTACLE", "NAVIGATION_LOST",
      "LOW_BATTERY", "LEAK",         "COMMAND_TIMEOUT", "OPERATOR", "OTHER"};
  return nameOf(kNames, reason);
}

ControllerNavigation ControllerNavigation::fromState(const VehicleState& state, double altitude,
                                                     double stamp) {
  ControllerNavigation nav;
  nav.position = state.position;
  nav.yaw = state.yaw;
  nav.surge = state.surge;
  nav.sway = state.sway;
  nav.heave = state.heave;
  nav.yaw_rate = state.yaw_rate;
  nav.altitude = altitude;
  nav.stamp = stamp;
  return nav;
}

bool ControllerNavigation::valid() const {
  return position.allFinite() && std::isfinite(yaw) && std::isfinite(surge) &&
         std::isfinite(sway) && std::isfinite(heave) && std::isfinite(yaw_rate) &&
         std::isfinite(altitude) && std::isfinite(stamp);
}

bool ControllerStatusReport::differsInState(const ControllerStatusReport& other) const {
  return active_command_id != other.active_command_id || state != other.state ||
         reached != other.reached || safety_maneuver != other.safety_maneuver ||
         safety_reason != other.safety_reason;
}

const config::OptionTable<ControllerOptions>& ControllerOptions::table() {
  using config::Range;
  using C = ControllerOptions;
  const Range gain = Range::atLeast(0.0);
  static const config::OptionTable<C> kTable = {
      {"heading_kp", &C::heading_kp, "heading PID proportional gain", "N m/rad", gain},
      {"heading_ki", &C::heading_ki, "heading PID integral gain", "N m/(rad s)", gain},
      {"heading_kd", &C::heading_kd, "heading PID yaw-rate damping", "N m/(rad/s)", gain},
      {"heading_integral_limit", &C::heading_integral_limit, "bound of the heading integral term",
       "N m", gain},
      {"depth_kp", &C::depth_kp, "depth PI proportional gain", "N/m", gain},
      {"depth_ki", &C::depth_ki, "depth PI integral gain", "N/(m s)", gain},
      {"depth_kd", &C::depth_kd, "depth heave-velocity damping", "N/(m/s)", gain},
      {"depth_integral_limit", &C::depth_integral_limit, "bound of the depth integral term", "N",
       gain},
      {"surge_kp", &C::surge_kp, "surge-speed PI proportional gain", "N/(m/s)", gain},
      {"surge_ki", &C::surge_ki, "surge-speed PI integral gain", "N/m", gain},
      {"surge_integral_limit", &C::surge_integral_limit, "bound of the surge integral term", "N",
       gain},
      {"default_surge_speed", &C::default_surge_speed,
       "WAYPOINT speed when the command's surge_speed is 0", "m/s", Range::aboveUpTo(0, 5)},
      {"max_surge_speed", &C::max_surge_speed, "largest commanded surge speed accepted", "m/s",
       Range::aboveUpTo(0, 5)},
      {"default_tolerance", &C::default_tolerance,
       "WAYPOINT tolerance when the command's is 0, and the HOLD radius", "m",
       Range::aboveUpTo(0, 100)},
      {"slow_down_radius", &C::slow_down_radius,
       "horizontal distance to a waypoint where the speed starts ramping down", "m",
       Range::aboveUpTo(0, 1000)},
      {"turn_in_place_angle", &C::turn_in_place_angle,
       "heading error beyond which the vehicle turns on the spot (pi/2: speed * cos(error))", "rad",
       Range::aboveUpTo(0, M_PI / 2)},
      {"min_approach_fraction", &C::min_approach_fraction,
       "floor of the slow-down ramp, as a fraction of the commanded speed", "",
       Range::aboveUpTo(0, 1)},
      {"hold_speed", &C::hold_speed, "speed to return to a held position", "m/s",
       Range::aboveUpTo(0, 5)},
      {"surface_depth", &C::surface_depth, "SURFACE is reached at or above this depth", "m",
       Range::closed(0, 100)},
      {"max_depth", &C::max_depth, "deeper starts the MAX_DEPTH safety manoeuvre", "m",
       Range::aboveUpTo(0, 10000)},
      {"min_altitude", &C::min_altitude,
       "a known altitude below this starts the MIN_ALTITUDE safety manoeuvre", "m",
       Range::closed(0, 1000)},
      {"navigation_timeout", &C::navigation_timeout,
       "without nav/odometry this long starts the NAVIGATION_LOST safety manoeuvre", "s",
       Range::aboveUpTo(0, 3600)},
      {"safety_clear_time", &C::safety_clear_time,
       "a safety condition gone this long ends the manoeuvre (the command is dropped)", "s",
       Range::closed(0, 3600)},
      {"breadcrumb_spacing", &C::breadcrumb_spacing,
       "distance between the recent positions kept to back away along from rock above", "m",
       Range::aboveUpTo(0, 100)},
      {"breadcrumb_length", &C::breadcrumb_length,
       "length of the trail of recent positions kept to back away along", "m",
       Range::closed(0, 10000)},
      {"retreat_speed", &C::retreat_speed,
       "reversing speed when a safety manoeuvre backs away from rock above", "m/s",
       Range::aboveUpTo(0, 5)},
      {"overhead_margin", &C::overhead_margin,
       "distance kept below known rock when the MAX_DEPTH manoeuvre rises under it", "m",
       Range::closed(0, 100)},
      {"altitude_time_constant", &C::altitude_time_constant,
       "low-pass time constant of the altitude mode's depth target (DVL noise)", "s",
       Range::closed(0, 600)},
      {"altitude_max_rate", &C::altitude_max_rate,
       "fastest descent of the altitude mode's depth target", "m/s", Range::aboveUpTo(0, 10)},
  };
  return kTable;
}

void ControllerOptions::check() const {
  config::checkOptions<ConfigError>(*this, table(), "controller.");
  if (default_surge_speed > max_surge_speed) {
    throw ConfigError("controller.default_surge_speed: " + number(default_surge_speed) +
                      " m/s exceeds controller.max_surge_speed " + number(max_surge_speed));
  }
  if (fault_action != FaultAction::STOP && fault_action != FaultAction::HOLD_DEPTH) {
    throw ConfigError("controller.fault_action: unknown value " +
                      std::to_string(static_cast<uint32_t>(fault_action)));
  }
  try {
    model.check();
  } catch (const ConfigError& e) {
    // Name the field as the controller knows it: "vehicle.x" -> "controller.model.x".
    std::string message = e.what();
    if (message.rfind("vehicle.", 0) == 0) message = "controller.model." + message.substr(8);
    throw ConfigError(message);
  }
}

LowLevelController::LowLevelController(const ControllerOptions& options) : options_(options) {
  options_.check();
}

bool LowLevelController::setNavigation(const ControllerNavigation& navigation, double now) {
  if (!navigation.valid()) return false;
  // The depth rate measured by the depth (pressure) itself, low-pass filtered: the depth loop's
  // damping while the DVL has no lock, when the estimate's heave is a held value.
  const double dt = navigation_ ? navigation.stamp - navigation_->stamp : 0.0;
  if (dt > 0.0) {  // by the estimates' stamps: samples may arrive in bursts
    const double rate = (navigation.position.z() - navigation_->position.z()) / dt;
    depth_rate_ += dt / (kDepthRateTimeConstant + dt) * (rate - depth_rate_);
  }
  navigation_ = navigation;
  navigation_time_ = now;
  if (!status_.safety_maneuver) recordBreadcrumb(navigation.position);
  status_.depth = navigation.position.z();
  status_.altitude = navigation.altitude;
  return true;
}

std::optional<std::string> LowLevelController::validate(const ControlCommand& command) const {
  const std::string prefix = "command " + std::to_string(command.command_id) + ": ";
  if (static_cast<uint32_t>(command.mode) > static_cast<uint32_t>(ControlMode::SURFACE)) {
    return prefix + "mode: unknown value " + std::to_string(static_cast<uint32_t>(command.mode));
  }
  if (command.command_id == 0) return prefix + "command_id: must be >= 1 (0 means none)";
  const std::pair<const char*, double> values[] = {{"position.x", command.position.x()},
                                                   {"position.y", command.position.y()},
                                                   {"position.z", command.position.z()},
                                                   {"heading", command.heading},
                                                   {"depth", command.depth},
                                                   {"surge_speed", command.surge_speed},
                                                   {"tolerance", command.tolerance},
                                                   {"timeout", command.timeout},
                                                   {"altitude", command.altitude}};
  for (const auto& [name, value] : values) {
    if (!std::isfinite(value))
      return prefix + name + ": not a finite number (" + number(value) + ")";
  }
  if (command.tolerance < 0) {
    return prefix + "tolerance: must be >= 0 m, got " + number(command.tolerance);
  }
  if (command.timeout < 0)
    return prefix + "timeout: must be >= 0 s, got " + number(command.timeout);
  if (command.altitude < 0) {
    return prefix + "altitude: must be >= 0 m (0 = depth mode), got " + number(command.altitude);
  }
  const double max_depth = options_.max_depth;
  const double max_speed = options_.max_surge_speed;
  if (command.mode == ControlMode::WAYPOINT) {
    if (command.position.z() < 0) {
      return prefix + "position.z: " + number(command.position.z()) +
             " m is above the surface (z is depth, >= 0)";
    }
    if (command.position.z() > max_depth) {
      return prefix + "position.z: " + number(command.position.z()) +
             " m is deeper than max_depth " + number(max_depth) + " m";
    }
    if (command.surge_speed < 0 || command.surge_speed > max_speed) {
      return prefix + "surge_speed: must be in [0, " + number(max_speed) + "] m/s, got " +
             number(command.surge_speed);
    }
  }
  if (command.mode == ControlMode::SETPOINT) {
    if (command.depth < 0 || command.depth > max_depth) {
      return prefix + "depth: must be in [0, " + number(max_depth) + "] m, got " +
             number(command.depth);
    }
    if (std::abs(command.surge_speed) > max_speed) {
      return prefix + "surge_speed: must be in [-" + number(max_speed) + ", " + number(max_speed) +
             "] m/s, got " + number(command.surge_speed);
    }
  }
  return std::nullopt;
}

CommandResult LowLevelController::setCommand(const ControlCommand& command, double now) {
  if (command.mode == ControlMode::NONE) {
    return {CommandResult::Outcome::IGNORED, "mode NONE carries no command"};
  }
  if (auto problem = validate(command)) return {CommandResult::Outcome::REJECTED, *problem};
  if (command_.mode != ControlMode::NONE && command.command_id == command_.command_id) {
    return {CommandResult::Outcome::IGNORED,
            "command " + std::to_string(command.command_id) + " is already the active one"};
  }
  if (status_.safety_maneuver) {
    return {CommandResult::Outcome::REFUSED, "command " + std::to_string(command.command_id) +
                                                 ": refused during the " +
                                                 toString(status_.safety_reason) +
                                                 " safety manoeuvre (" + status_.safety_text + ")"};
  }

  command_ = command;
  if (command_.mode == ControlMode::WAYPOINT) {
    if (command_.tolerance == 0) command_.tolerance = options_.default_tolerance;
    if (command_.surge_speed == 0) command_.surge_speed = options_.default_surge_speed;
  }
  command_.heading = wrapAngle(command_.heading);
  command_start_ = now;
  status_.active_command_id = command.command_id;
  status_.reached = false;
  status_.distance_to_target = -1.0;
  hold_pending_ = false;
  returning_ = false;
  altitude_depth_.reset();
  leg_start_.reset();
  if (navigation_) leg_start_ = navigation_->position;
  resetIntegrals(false);  // the depth integral estimates the buoyancy error: keep it

  switch (command_.mode) {
    case ControlMode::STOP:
      status_.state = ControllerState::IDLE;
      break;
    case ControlMode::HOLD:
      status_.state = ControllerState::HOLDING;
      if (navigation_) {
        startHolding(navigation_->position, options_.default_tolerance, navigation_->yaw);
      } else {
        hold_pending_ = true;
      }
      break;
    case ControlMode::WAYPOINT:
      if (navigation_)
        status_.distance_to_target = (command_.position - navigation_->position).norm();
      status_.state = ControllerState::ACTIVE;
      break;
    default:
      status_.state = ControllerState::ACTIVE;
      break;
  }
  return {CommandResult::Outcome::ACCEPTED, ""};
}

void LowLevelController::resetIntegrals(bool depth_too) {
  heading_integral_ = 0.0;
  surge_integral_ = 0.0;
  if (depth_too) depth_integral_ = 0.0;
}

void LowLevelController::startHolding(const Eigen::Vector3d& point, double radius, double yaw) {
  hold_point_ = point;
  hold_radius_ = radius;
  hold_yaw_ = yaw;
  returning_ = false;
  hold_pending_ = false;
}

ThrusterCommand LowLevelController::update(double now) {
  if (!first_update_) first_update_ = now;
  const double dt = last_update_ ? std::clamp(now - *last_update_, 0.0, kMaxControlStep) : 0.0;
  last_update_ = now;

  updateSafety(now);
  if (status_.safety_maneuver) return safetyManoeuvre(dt);
  const bool running =
      status_.state == ControllerState::ACTIVE || status_.state == ControllerState::HOLDING;
  if (running && command_.timeout > 0 && !status_.reached &&
      now - command_start_ > command_.timeout) {
    status_.state = ControllerState::FAULT;
    status_.distance_to_target = -1.0;
    fault_depth_ = navigation_ ? navigation_->position.z() : 0.0;
  }
  if (!navigation_) return {};  // nothing to regulate on; NAVIGATION_LOST follows

  switch (status_.state) {
    case ControllerState::FAULT: {
      if (options_.fault_action == FaultAction::STOP) return {};
      Targets hold{navigation_->yaw, fault_depth_, 0.0};
      ThrusterCommand out = regulate(hold, dt);
      out.port = out.starboard = 0.0;
      return out;
    }
    case ControllerState::ACTIVE:
    case ControllerState::HOLDING:
      if (command_.mode == ControlMode::SURFACE) {
        if (navigation_->position.z() <= options_.surface_depth) status_.reached = true;
        return {0.0, 0.0, status_.reached ? 0.0 : -1.0};  // buoyancy keeps it up there
      }
      return regulate(guidance(dt), dt);
    default:
      return {};
  }
}

double LowLevelController::depthTarget(double commanded, double dt) {
  if (command_.altitude <= 0) return commanded;
  const ControllerNavigation& nav = *navigation_;
  // Without bottom lock before any target: the current depth, unless deeper than commanded.
  if (!altitude_depth_) altitude_depth_ = std::min(nav.position.z(), commanded);
  if (nav.altitude >= 0) {
    const double wanted =
        std::clamp(nav.position.z() + nav.altitude - command_.altitude, 0.0, commanded);
    const double alpha =
        options_.altitude_time_constant > 0 ? dt / (options_.altitude_time_constant + dt) : 1.0;
    // Rising to a seabed that comes up is never held back; descending is rate-limited.
    const double step = alpha * (wanted - *altitude_depth_);
    altitude_depth_ = *altitude_depth_ + std::min(step, options_.altitude_max_rate * dt);
  }
  altitude_depth_ = std::min(*altitude_depth_, commanded);
  return *altitude_depth_;
}

LowLevelController::Targets LowLevelController::guidance(double dt) {
  const ControllerNavigation& nav = *navigation_;
  switch (command_.mode) {
    case ControlMode::HOLD:
      if (hold_pending_) startHolding(nav.position, options_.default_tolerance, nav.yaw);
      return holdTargets();
    case ControlMode::SETPOINT:
      return {command_.heading, depthTarget(command_.depth, dt), command_.surge_speed};
    case ControlMode::WAYPOINT: {
      // In altitude mode the target's depth is the altitude's (reached in 3-D at that depth).
      Eigen::Vector3d target = command_.position;
      if (status_.state != ControllerState::HOLDING) target.z() = depthTarget(target.z(), dt);
      const double distance = (target - nav.position).norm();
      status_.distance_to_target = distance;
      if (status_.state == ControllerState::HOLDING) return holdTargets();
      if (distance <= command_.tolerance) {
        status_.reached = true;
        status_.state = ControllerState::HOLDING;
        startHolding(target, command_.tolerance, nav.yaw);
        return holdTargets();
      }
      if (!leg_start_) leg_start_ = nav.position;  // the command came before any navigation
      const bool depth_mode = command_.altitude <= 0.0;
      Targets targets{nav.yaw, depth_mode ? depthAlongLeg(target) : target.z(), 0.0};
      const Eigen::Vector2d horizontal = (target - nav.position).head<2>();
      const double range = horizontal.norm();
      // Right above or below the target the line of sight is undefined: only change depth.
      if (range > 0.5 * command_.tolerance) {
        targets.yaw = std::atan2(horizontal.y(), horizontal.x());
        const double ramp =
            std::clamp(range / options_.slow_down_radius, options_.min_approach_fraction, 1.0);
        // Turn first: full speed only when pointing at the target, none when it is abeam.
        targets.surge_speed = command_.surge_speed * ramp * underwayFraction(targets.yaw - nav.yaw);
      }
      return targets;
    }
    default:
      return {nav.yaw, nav.position.z(), 0.0};
  }
}

double LowLevelController::depthAlongLeg(const Eigen::Vector3d& target) const {
  const Eigen::Vector2d leg = (target - *leg_start_).head<2>();
  const double length = leg.norm();
  // A leg that is mostly a depth change (or one begun at the target) is flown as one.
  if (length <= 0.5 * command_.tolerance) return target.z();
  const double along = leg.dot((navigation_->position - *leg_start_).head<2>()) / length;
  const double progress = std::clamp((along + kLegDepthLead) / length, 0.0, 1.0);
  return leg_start_->z() + progress * (target.z() - leg_start_->z());
}

LowLevelController::Targets LowLevelController::holdTargets() {
  const ControllerNavigation& nav = *navigation_;
  const Eigen::Vector2d offset = (hold_point_ - nav.position).head<2>();
  const double range = offset.norm();
  // Hysteresis: drive back once outside the radius, stop again well inside it.
  if (range > hold_radius_) {
    returning_ = true;
  } else if (returning_ && range < 0.5 * hold_radius_) {
    returning_ = false;
    hold_yaw_ = nav.yaw;  // keep the heading it arrived with
  }
  if (!returning_) return {hold_yaw_, hold_point_.z(), 0.0};
  const double yaw = std::atan2(offset.y(), offset.x());
  return {yaw, hold_point_.z(), options_.hold_speed * underwayFraction(yaw - nav.yaw)};
}

double LowLevelController::underwayFraction(double heading_error) const {
  const double limit = std::cos(options_.turn_in_place_angle);
  const double alignment = std::cos(wrapAngle(heading_error));
  return alignment <= limit ? 0.0 : (alignment - limit) / (1.0 - limit);
}

ThrusterCommand LowLevelController::regulate(const Targets& targets, double dt) {
  const ControllerNavigation& nav = *navigation_;
  const ControllerOptions& o = options_;

  const double yaw_error = wrapAngle(targets.yaw - nav.yaw);
  if (std::abs(yaw_error) < kHeadingIntegralBand && std::abs(nav.yaw_rate) < kYawRateIntegralBand) {
    heading_integral_ =
        clampIntegral(heading_integral_ + yaw_error * dt, o.heading_ki, o.heading_integral_limit);
  }
  const double yaw_moment =
      o.heading_kp * yaw_error + o.heading_ki * heading_integral_ - o.heading_kd * nav.yaw_rate;

  const double depth_error = targets.depth - nav.position.z();
  // A held heave would be a constant push against the depth loop (an offset of kd/kp times it).
  const double depth_rate = nav.velocity_measured ? nav.heave : depth_rate_;
  if (std::abs(depth_error) < kDepthIntegralBand && std::abs(depth_rate) < kHeaveIntegralBand) {
    depth_integral_ =
        clampIntegral(depth_integral_ + depth_error * dt, o.depth_ki, o.depth_integral_limit);
  }
  // Buoyancy pushes up (-z): the vertical thruster holds it with as much force down.
  const double heave_force = o.model.net_buoyancy + o.depth_kp * depth_error +
                             o.depth_ki * depth_integral_ - o.depth_kd * depth_rate;

  // Without a measured velocity there is nothing to close the loop on: feed-forward, with the
  // model correction learnt so far.
  const double speed_error = nav.velocity_measured ? targets.surge_speed - nav.surge : 0.0;
  if (nav.velocity_measured && std::abs(speed_error) < kSurgeIntegralBand) {
    surge_integral_ =
        clampIntegral(surge_integral_ + speed_error * dt, o.surge_ki, o.surge_integral_limit);
  }
  const double surge_force = o.model.surgeDrag(targets.surge_speed) + o.surge_kp * speed_error +
                             o.surge_ki * surge_integral_;

  return allocate(surge_force, yaw_moment, heave_force);
}

ThrusterCommand LowLevelController::allocate(double surge_force, double yaw_moment,
                                             double heave_force) const {
  const VehicleModel& m = options_.model;
  // port = X/2 + N/s and starboard = X/2 - N/s give surge X and yaw moment s/2 (port -
  // starboard) = N. The moment comes first; surge gets what thrust is left.
  const double moment = std::clamp(yaw_moment, -m.maxYawMoment(), m.maxYawMoment());
  double differential = moment / m.thruster_spacing;
  if (surge_force <= 0.0) {
    // Except when stopping: the thrusters push harder forward than in reverse, so a full
    // differential drives the vehicle on while it turns and swings it wide by its turning
    // radius. It stops first, then turns on the spot.
    const double braking = std::max(surge_force, -2.0 * m.max_thrust_reverse);
    const double cap = m.max_thrust_reverse + 0.5 * braking;
    differential = std::clamp(differential, -cap, cap);
  }
  const double lowest = 2.0 * (-m.max_thrust_reverse + std::abs(differential));
  const double highest = 2.0 * (m.max_thrust_forward - std::abs(differential));
  const double surge = std::clamp(surge_force, lowest, highest);
  return {m.commandForThrust(0.5 * surge + differential),
          m.commandForThrust(0.5 * surge - differential), m.commandForThrust(heave_force)};
}

}  // namespace auv::control
