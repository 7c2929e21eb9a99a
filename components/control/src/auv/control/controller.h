#pragma once
// The vehicle's low-level controller as pure logic (no DDS): it turns a navigation estimate and
// a command (a mirror of auv::msg::ControllerCommand) into thruster setpoints and a status (a
// mirror of auv::msg::ControllerStatus), and runs the safety manoeuvres itself. The
// `controller` component wraps it; tests close the loop with VehicleDynamics (vehicle_model.h).
//
// Control laws (forces in the body frame, then allocated to the three thrusters):
//   heading  N = kp e + ki int(e) - kd r          e = wrap(target yaw - yaw), r = yaw rate
//   depth    Z = B + kp e + ki int(e) - kd w      B = the model's net buoyancy (feed-forward)
//   surge    X = D(u*) + kp (u* - u) + ki int(..) D = the model's surge drag at speed u*
//            (D(u*) + ki int(..), integral frozen, while the velocity is not measured)
// Integrals only accumulate near the setpoint and nearly at rest there (conditional
// integration): they remove steady model errors without winding up during large manoeuvres. The yaw
// moment has priority over surge when the horizontal pair saturates, so the vehicle turns first and
// then accelerates.
//
// Safety manoeuvres (state SAFETY_MANEUVER): navigation older than navigation_timeout
// (NAVIGATION_LOST), depth > max_depth (MAX_DEPTH), known altitude < min_altitude
// (MIN_ALTITUDE), in that priority. What the vehicle does depends on the water above it, as the
// overhead probe (setOverheadProbe; the component reads it from the map) reports it:
//   open above (no known rock up to the surface; unknown counts as open, the paper's assumption,
//   and no probe means open): vertical full up, horizontal off (ascend, as always);
//   rock above: never up into it.
//     MIN_ALTITUDE  hold depth and back away (reversing) along the breadcrumb trail of the
//                   vehicle's recent positions until the water above is open, then ascend; at
//                   the end of the trail, hold position and depth.
//     MAX_DEPTH     rise to a little above max_depth, but keep overhead_margin below the rock.
//     NAVIGATION_LOST  no position to follow a trail with: horizontal off, the vertical thruster
//                   only balances the buoyancy (holds depth without a depth loop).
// status.safety_text says the condition and the action ("...; backing away: rock 1.2 m above").
// The manoeuvre ends once no condition has held for safety_clear_time; the interrupted command is
// then dropped (state IDLE; under rock HOLDING where it is instead, since thrusters off would let
// the buoyancy lift it into the rock): the mission handler decides what comes next. Commands are
// refused meanwhile.
//
// Altitude mode (command altitude > 0, WAYPOINT and SETPOINT, COLA2-style): the depth target is
// depth + (measured altitude - commanded altitude), never deeper than the commanded depth,
// low-passed (altitude_time_constant) and descending at most altitude_max_rate, so DVL noise
// does not shake it. Without bottom lock (altitude < 0) the last target is kept (first: the
// current depth, if shallower than commanded): shallower than commanded is the safe side, and
// descending blind to the commanded depth could meet the seabed the DVL lost.

#include <cstdint>
#include <deque>
#include <functional>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "auv/control/vehicle_model.h"

namespace auv::control {

// Same values, in the same order, as the IDL enums (the component static_asserts it).
enum class ControlMode : uint32_t { NONE, STOP, HOLD, WAYPOINT, SETPOINT, SURFACE };
enum class ControllerState : uint32_t { UNKNOWN, IDLE, ACTIVE, HOLDING, SAFETY_MANEUVER, FAULT };
enum class SafetyReason : uint32_t {
  NONE,
  MIN_ALTITUDE,
  MAX_DEPTH,
  OBSTACLE,
  NAVIGATION_LOST,
  LOW_BATTERY,
  LEAK,
  COMMAND_TIMEOUT,
  OPERATOR,
  OTHER
};

const char* toString(ControlMode mode);
const char* toString(ControllerState state);
const char* toString(SafetyReason reason);

/// What to do after a command timed out (state FAULT) until the next command.
enum class FaultAction : uint32_t {
  STOP,        ///< all thrusters off (the vehicle drifts up slowly)
  HOLD_DEPTH,  ///< horizontal thrusters off, keep the depth of the moment of the fault
};

/// The navigation estimate the controller acts on.
struct ControllerNavigation {
  Eigen::Vector3d position{0, 0, 0};  ///< m NED (z = depth)
  double yaw = 0.0;                   ///< rad, 0 = north
  double surge = 0.0;                 ///< m/s, body x
  double sway = 0.0;                  ///< m/s, body y
  double heave = 0.0;                 ///< m/s, body z (down)
  double yaw_rate = 0.0;              ///< rad/s
  double altitude = -1.0;             ///< m above the seabed; < 0 = unknown
  double stamp = 0.0;                 ///< s, time of the estimate (informative only)
  /// False while the filter holds the velocity instead of measuring it (DVL without bottom
  /// lock). The surge loop then runs on its feed-forward alone: closed on a held velocity it
  /// drives the vehicle off unseen (to slow down from a held 0.3 m/s it reverses, faster and
  /// faster, while the estimate still says 0.3 m/s forward).
  bool velocity_measured = true;

  /// A perfect estimate of `state` (ground truth).
  static ControllerNavigation fromState(const VehicleState& state, double altitude, double stamp);
  /// True when every field is finite.
  bool valid() const;
};

/// Mirror of auv::msg::ControllerCommand. Conventions: WAYPOINT tolerance 0 = the options'
/// default_tolerance, WAYPOINT surge_speed 0 = default_surge_speed, timeout 0 = no limit.
struct ControlCommand {
  uint64_t command_id = 0;  ///< >= 1, unique per issuer run
  ControlMode mode = ControlMode::NONE;
  Eigen::Vector3d position{0, 0, 0};  ///< m NED, WAYPOINT target (z = depth)
  double heading = 0.0;               ///< rad, SETPOINT yaw
  double depth = 0.0;                 ///< m, SETPOINT depth
  double surge_speed = 0.0;           ///< m/s, WAYPOINT (> 0) and SETPOINT speed
  double tolerance = 0.0;             ///< m, WAYPOINT reached within this 3-D distance
  double timeout = 0.0;               ///< s, FAULT if not reached after this long; 0 = none
  /// m, > 0: altitude mode (WAYPOINT, SETPOINT), keep this height above the seabed, never deeper
  /// than the commanded depth; 0 = depth mode.
  double altitude = 0.0;
};

/// Distance (m) from a position up to the first known rock in the water column above it (the
/// vehicle's hull radius plus a margin wide), +infinity when the column is open up to the
/// surface. Unknown space counts as open.
using OverheadProbe = std::function<double(const Eigen::Vector3d& position)>;

/// Mirror of auv::msg::ControllerStatus.
struct ControllerStatusReport {
  uint64_t active_command_id = 0;  ///< command executing or last finished; 0 = none
  ControllerState state = ControllerState::IDLE;
  bool reached = false;  ///< the WAYPOINT (or SURFACE) goal was reached
  bool safety_maneuver = false;
  SafetyReason safety_reason = SafetyReason::NONE;
  std::string safety_text;  ///< detail with the numbers, empty when no manoeuvre
  /// What the manoeuvre does now: "ascending", "backing away", "rising", "holding" (also at the
  /// end of safety_text); empty when no manoeuvre.
  std::string safety_action;
  double depth = 0.0;                ///< m, last known depth
  double altitude = -1.0;            ///< m, last known altitude; < 0 = unknown
  double distance_to_target = -1.0;  ///< m, 3-D distance to the WAYPOINT; < 0 = not applicable

  /// True when the fields that make a status worth publishing at once differ (state, reached,
  /// safety flag and reason, command id); measurements are not compared.
  bool differsInState(const ControllerStatusReport& other) const;
};

/// Outcome of LowLevelController::setCommand.
struct CommandResult {
  enum class Outcome {
    ACCEPTED,  ///< now the active command
    IGNORED,   ///< mode NONE, or the active command_id again: nothing to do
    REJECTED,  ///< malformed; `reason` names the field
    REFUSED,   ///< well-formed but not executable now (a safety manoeuvre is running)
  };
  Outcome outcome = Outcome::REJECTED;
  std::string reason;  ///< why not accepted
  bool accepted() const { return outcome == Outcome::ACCEPTED; }
};

struct ControllerOptions {
  // Heading PID (yaw moment).
  double heading_kp = 10.0;             ///< N m/rad
  double heading_ki = 0.5;              ///< N m/(rad s)
  double heading_kd = 20.0;             ///< N m/(rad/s), yaw-rate damping
  double heading_integral_limit = 2.0;  ///< N m, bound of the integral term
  // Depth PI with heave damping (vertical force, + down).
  double depth_kp = 60.0;             ///< N/m
  double depth_ki = 6.0;              ///< N/(m s)
  double depth_kd = 120.0;            ///< N/(m/s), heave damping
  double depth_integral_limit = 8.0;  ///< N, bound of the integral term
  // Surge PI around the drag-model feed-forward.
  double surge_kp = 60.0;             ///< N/(m/s)
  double surge_ki = 10.0;             ///< N/m
  double surge_integral_limit = 8.0;  ///< N, bound of the integral term

  // Guidance.
  double default_surge_speed = 0.8;     ///< m/s, WAYPOINT speed when the command gives 0
  double max_surge_speed = 1.1;         ///< m/s, largest commanded speed accepted
  double default_tolerance = 1.0;       ///< m, WAYPOINT tolerance when 0; HOLD radius
  double slow_down_radius = 3.0;        ///< m, horizontal distance where WAYPOINT speed ramps down
  double min_approach_fraction = 0.25;  ///< of the commanded speed, floor of the ramp
  /// rad, in (0, pi/2]: with a larger heading error the vehicle turns on the spot; below, the
  /// speed grows to full at zero error. Why: moving while turning round swings it sideways by
  /// its turning radius, which a narrow passage does not have (pi/2: speed * cos(error)).
  double turn_in_place_angle = M_PI / 6;
  double hold_speed = 0.2;     ///< m/s, speed to return to a held position
  double surface_depth = 0.3;  ///< m, SURFACE is reached at or above this depth

  // Safety.
  double max_depth = 50.0;          ///< m, deeper starts the MAX_DEPTH manoeuvre
  double min_altitude = 1.0;        ///< m, a known altitude below starts MIN_ALTITUDE
  double navigation_timeout = 1.0;  ///< s, without navigation starts NAVIGATION_LOST
  double safety_clear_time = 3.0;   ///< s, conditions gone this long end the manoeuvre
  FaultAction fault_action = FaultAction::HOLD_DEPTH;  ///< after a command timeout
  double breadcrumb_spacing = 1.0;  ///< m, distance between the positions kept as the trail
  double breadcrumb_length = 30.0;  ///< m, length of the trail kept to back away along
  double retreat_speed = 0.3;       ///< m/s, reversing speed when backing away from rock above
  double overhead_margin = 0.5;     ///< m, kept below known rock when rising (MAX_DEPTH)

  // Altitude mode.
  double altitude_time_constant = 2.0;  ///< s, low-pass of the altitude-derived depth target
  double altitude_max_rate = 0.3;       ///< m/s, fastest descent of that target

  /// Vehicle model used for feed-forward (drag, buoyancy) and thrust allocation.
  VehicleModel model;

  /// The numeric fields with meaning, unit and range, declared once: check() and the
  /// controller component's `controller.*` parameters (so `auv run controller --help`).
  static const config::OptionTable<ControllerOptions>& table();
  /// Throws ConfigError naming the field ("controller.depth_kp: ..."): a range of table(),
  /// default_surge_speed above max_surge_speed, the model's check().
  void check() const;
};

/// Modes and states:
///   WAYPOINT  ACTIVE: line-of-sight heading to the target, speed ramped down inside
///             slow_down_radius and scaled down with the heading error, to zero beyond
///             turn_in_place_angle (it turns before it goes); in depth mode the depth follows
///             the straight leg from where the command began to the target, by horizontal
///             progress (the planner checked that leg, not a climb first and a run after);
///             within `tolerance` (3-D) -> reached, HOLDING at the target.
///   HOLD      HOLDING at the position of the moment: stopped, heading and depth kept; drifted
///             further than default_tolerance it drives back at hold_speed.
///   SETPOINT  ACTIVE: heading, depth and surge speed kept until replaced.
///   SURFACE   ACTIVE: vertical thruster full up until depth <= surface_depth (reached), then
///             off (the positive buoyancy keeps it there).
///   STOP      IDLE: thrusters off.
/// A command not reached after its `timeout` -> FAULT (see FaultAction) until the next one.
class LowLevelController {
 public:
  /// Throws ConfigError if the options do not pass check().
  explicit LowLevelController(const ControllerOptions& options);

  /// Takes a new navigation estimate received at `now` (s). Returns false and ignores it when
  /// a field is not finite (a broken estimate counts as missing navigation).
  bool setNavigation(const ControllerNavigation& navigation, double now);
  /// Replaces the active command (see CommandResult). A malformed command is rejected with
  /// the field named and the previous command kept; a repeated command_id is ignored.
  CommandResult setCommand(const ControlCommand& command, double now);
  /// Runs one control step at `now` (s, monotonic); returns the thruster setpoints.
  ThrusterCommand update(double now);

  const ControllerStatusReport& status() const { return status_; }
  const ControllerOptions& options() const { return options_; }
  /// The active command (mode NONE when there is none).
  const ControlCommand& command() const { return command_; }

  /// Checks a command without applying it; returns the problem naming the field, if any.
  std::optional<std::string> validate(const ControlCommand& command) const;

  /// Where the water above is open (see OverheadProbe); asked only during safety manoeuvres.
  /// Without one the water above always counts as open.
  void setOverheadProbe(OverheadProbe probe) { overhead_probe_ = std::move(probe); }
  /// The breadcrumb trail, oldest first (positions at least breadcrumb_spacing apart, recorded
  /// outside safety manoeuvres).
  const std::deque<Eigen::Vector3d>& trail() const { return trail_; }

 private:
  struct Targets {  // what the guidance asks of the three loops
    double yaw = 0.0;
    double depth = 0.0;
    double surge_speed = 0.0;
  };

  // controller_safety.cc: conditions, the manoeuvre's action, the breadcrumb trail.
  void updateSafety(double now);
  ThrusterCommand safetyManoeuvre(double dt);
  /// Backs away along the trail; false when it is used up (the caller holds).
  bool retreatTargets(Targets& targets);
  void recordBreadcrumb(const Eigen::Vector3d& position);
  double overheadClearance(const Eigen::Vector3d& position) const;

  void startHolding(const Eigen::Vector3d& point, double radius, double yaw);
  Targets guidance(double dt);
  /// The depth to keep for a command depth of `commanded` (altitude mode, or `commanded`).
  double depthTarget(double commanded, double dt);
  /// The depth of the leg from leg_start_ to `target` at the vehicle's horizontal progress.
  double depthAlongLeg(const Eigen::Vector3d& target) const;
  Targets holdTargets();
  /// Fraction of the speed to make good with `heading_error` (see turn_in_place_angle).
  double underwayFraction(double heading_error) const;
  ThrusterCommand regulate(const Targets& targets, double dt);
  ThrusterCommand allocate(double surge_force, double yaw_moment, double heave_force) const;
  void resetIntegrals(bool depth_too);

  ControllerOptions options_;
  ControllerStatusReport status_;
  ControlCommand command_;
  double command_start_ = 0.0;

  std::optional<ControllerNavigation> navigation_;
  double navigation_time_ = 0.0;        // s, when the last valid estimate arrived
  std::optional<double> first_update_;  // s, start of the navigation_timeout before any
  std::optional<double> last_update_;
  std::optional<double> condition_seen_;  // s, last time a safety condition held

  // Holding (HOLD, or a reached WAYPOINT).
  Eigen::Vector3d hold_point_{0, 0, 0};
  double hold_radius_ = 1.0;
  double hold_yaw_ = 0.0;
  bool hold_pending_ = false;  // HOLD arrived before any navigation: take the next position
  bool returning_ = false;     // outside the hold radius, driving back
  double fault_depth_ = 0.0;

  double heading_integral_ = 0.0;  // rad s
  double depth_integral_ = 0.0;    // m s
  double surge_integral_ = 0.0;    // m
  double depth_rate_ = 0.0;        // m/s, from successive depths (setNavigation)

  std::optional<double> altitude_depth_;      // m, smoothed depth target of altitude mode
  std::optional<Eigen::Vector3d> leg_start_;  // where the active WAYPOINT command began

  // Safety manoeuvres.
  OverheadProbe overhead_probe_;
  std::deque<Eigen::Vector3d> trail_;      // breadcrumbs, oldest first
  std::string condition_text_;             // the condition part of safety_text
  std::optional<double> manoeuvre_depth_;  // m, depth held under rock (set at the first need)
};

}  // namespace auv::control
