#include "auv/control/components/controller_component.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "auv/control/components/odometry_conversion.h"
#include "auv/interfaces/msg_time.h"
#include "auv/interfaces/option_parameters.h"

namespace auv::control {
namespace {

// The mirrors in controller.h must keep the IDL's numbering: messages are cast, not mapped.
static_assert(static_cast<uint32_t>(ControlMode::SURFACE) == msg::CONTROL_MODE_SURFACE);
static_assert(static_cast<uint32_t>(ControlMode::WAYPOINT) == msg::CONTROL_MODE_WAYPOINT);
static_assert(static_cast<uint32_t>(ControllerState::FAULT) == msg::CONTROLLER_STATE_FAULT);
static_assert(static_cast<uint32_t>(ControllerState::SAFETY_MANEUVER) ==
              msg::CONTROLLER_STATE_SAFETY_MANEUVER);
static_assert(static_cast<uint32_t>(SafetyReason::NAVIGATION_LOST) ==
              msg::SAFETY_REASON_NAVIGATION_LOST);
static_assert(static_cast<uint32_t>(SafetyReason::OTHER) == msg::SAFETY_REASON_OTHER);

// The part of the vehicle model the controller uses (feed-forward and allocation), declared as
// `controller.model.<name>` with the model's own meaning, unit and range.
config::OptionTable<VehicleModel> feedForwardModel() {
  const std::vector<std::string> used = {"drag_linear_surge",  "drag_quadratic_surge",
                                         "max_thrust_forward", "max_thrust_reverse",
                                         "thruster_spacing",   "net_buoyancy"};
  config::OptionTable<VehicleModel> table;
  for (const auto& option : VehicleModel::table()) {
    if (std::find(used.begin(), used.end(), option.name) != used.end()) table.push_back(option);
  }
  return table;
}

const char* faultActionName(FaultAction action) {
  return action == FaultAction::STOP ? "stop" : "hold_depth";
}

void stamp(msg::Header& header, const interfaces::Clock& clock, const char* frame) {
  header.stamp(interfaces::toMsgTime(clock.nowNs()));
  header.frame_id(frame);
}

}  // namespace

const config::OptionTable<ControllerComponent::Options>& ControllerComponent::Options::table() {
  using config::Range;
  static const config::OptionTable<Options> kTable = {
      {"control_rate", &Options::control_rate,
       "control steps and control/thrusters messages per second", "Hz", Range::closed(1.0, 1000.0)},
      {"status_rate", &Options::status_rate,
       "periodic control/status messages per second (also sent on every change)", "Hz",
       Range::closed(0.01, 100.0)},
      {"map_id", &Options::map_id, "OctomapUpdate.map_id followed (rock above the vehicle)"},
      {"map_resolution", &Options::map_resolution, "leaf size of the map on map/update", "m",
       Range::closed(0.01, 10.0)},
      {"overhead_radius", &Options::overhead_radius,
       "radius of the column above the vehicle that must be free of known rock (occupied cell "
       "centres) for a safety manoeuvre to ascend: hull radius + margin, below the planner's "
       "clearance",
       "m", Range::closed(0.0, 100.0)},
  };
  return kTable;
}

void ControllerComponent::configure(interfaces::Node& node) {
  node_ = &node;
  auto& p = node.parameters();
  interfaces::declareOptions(p, "", Options::table(), options_, /*read_only=*/true);
  interfaces::declareOptions(p, "controller.", ControllerOptions::table(), options_.controller,
                             /*read_only=*/false);
  interfaces::declareOptions(p, "controller.model.", feedForwardModel(), options_.controller.model,
                             /*read_only=*/false);
  const std::string fault_action = p.declare<std::string>(
      "controller.fault_action", faultActionName(options_.controller.fault_action),
      {"after a command timeout: hold_depth (horizontal thrusters off, keep depth) or stop (all "
       "thrusters off)",
       "",
       {},
       {},
       {"hold_depth", "stop"},
       false});
  options_.controller.fault_action =
      fault_action == "stop" ? FaultAction::STOP : FaultAction::HOLD_DEPTH;
  controller_ = std::make_unique<LowLevelController>(options_.controller);  // check()s
  last_reported_ = controller_->status();
  map_ = std::make_unique<MapFollower>(
      options_.map_id, options_.map_resolution,
      [this](uint64_t sequence, const std::string& error) {
        AUV_WARN(node_->logger(), "map update "
                                      << sequence
                                      << " not used for the water above the vehicle: " << error);
      });
  controller_->setOverheadProbe([this](const Eigen::Vector3d& position) {
    // While an update is being applied, the answer of the step before (50 ms and a few cm
    // ago); NaN, which the controller counts as rock right above, before the first one.
    map_->tryRead([&](const octomap::OcTree& tree) {
      last_overhead_clearance_ = overheadClearance(tree, position, options_.overhead_radius);
    });
    return last_overhead_clearance_;
  });

  thrusters_pub_ = node.createPublisher<msg::ThrusterSetpoints>("control/thrusters",
                                                                interfaces::sensorDataQos());
  status_pub_ =
      node.createPublisher<msg::ControllerStatus>("control/status", interfaces::stateQos());
  command_sub_ = node.createSubscription<msg::ControllerCommand>(
      "control/waypoint", interfaces::commandQos(),
      std::function<void(const msg::ControllerCommand&)>(
          [this](const msg::ControllerCommand& m) { onCommand(m); }));
  // Best effort: control needs the newest estimate; a reliable reader holds newer ones back
  // while a lost one is repaired (0.2-0.4 s of wall time on a loaded machine).
  odometry_sub_ = node.createSubscription<msg::Odometry>(
      "nav/odometry", interfaces::sensorDataQos(),
      std::function<void(const msg::Odometry&)>([this](const msg::Odometry& m) { onOdometry(m); }),
      interfaces::SubscriptionOptions{interfaces::CallbackThread::MIDDLEWARE});
  // Taken on the executor (a copy), applied on the follower's thread: never in a control step.
  map_sub_ = node.createSubscription<msg::OctomapUpdate>(
      "map/update", interfaces::mapQos(),
      std::function<void(const msg::OctomapUpdate&)>(
          [this](const msg::OctomapUpdate& update) { map_->push(update); }));
}

double ControllerComponent::overheadClearance(const octomap::OcTree& map,
                                              const Eigen::Vector3d& position, double radius) {
  double clearance = std::numeric_limits<double>::infinity();
  if (position.z() <= 0.0 || map.getRoot() == nullptr) return clearance;
  const octomap::point3d low(static_cast<float>(position.x() - radius),
                             static_cast<float>(position.y() - radius), 0.0f);
  const octomap::point3d high(static_cast<float>(position.x() + radius),
                              static_cast<float>(position.y() + radius),
                              static_cast<float>(position.z()));
  for (auto it = map.begin_leafs_bbx(low, high), end = map.end_leafs_bbx(); it != end; ++it) {
    if (!map.isNodeOccupied(*it)) continue;
    // Cell centres within the radius, as the planner measures clearance: a wall the planner
    // keeps its clearance from is beside the vehicle, not above it.
    const Eigen::Vector2d offset(it.getX() - position.x(), it.getY() - position.y());
    if (offset.norm() > radius) continue;
    const double bottom = it.getZ() + 0.5 * it.getSize();  // the cell's deep face (z down)
    if (bottom > position.z()) continue;                   // not wholly above the vehicle
    clearance = std::min(clearance, std::max(0.0, position.z() - bottom));
  }
  return clearance;
}

void ControllerComponent::activate() {
  control_timer_ = node_->createTimer(1.0 / options_.control_rate, [this] { controlStep(); });
  status_timer_ = node_->createTimer(1.0 / options_.status_rate, [this] { publishStatus(); });
  const ControllerOptions& c = options_.controller;
  AUV_INFO(node_->logger(), "controlling at " << options_.control_rate << " Hz; max_depth "
                                              << c.max_depth << " m, min_altitude "
                                              << c.min_altitude << " m, navigation_timeout "
                                              << c.navigation_timeout << " s");
}

void ControllerComponent::deactivate() {
  if (control_timer_) control_timer_->cancel();
  if (status_timer_) status_timer_->cancel();
  control_timer_.reset();
  status_timer_.reset();
  if (thrusters_pub_) publishThrusters({});  // leave the thrusters stopped
}

void ControllerComponent::cleanup() {
  command_sub_.reset();
  odometry_sub_.reset();
  map_sub_.reset();
  thrusters_pub_.reset();
  status_pub_.reset();
  controller_.reset();
  map_.reset();
}

void ControllerComponent::onOdometry(const msg::Odometry& odometry) {
  std::lock_guard<std::mutex> lock(odometry_mutex_);
  latest_odometry_ = odometry;
  latest_odometry_arrival_ = node_->clock().nowSeconds();
}

void ControllerComponent::applyOdometry() {
  msg::Odometry odometry;
  double arrival = 0.0;
  {
    std::lock_guard<std::mutex> lock(odometry_mutex_);
    if (!latest_odometry_) return;
    odometry = std::move(*latest_odometry_);
    latest_odometry_.reset();
    arrival = latest_odometry_arrival_;
  }
  bool orientation_ok = false;
  const ControllerNavigation nav = toControllerNavigation(odometry, orientation_ok);
  // A zero quaternion (an unset orientation) has no yaw: treat it as a broken estimate.
  if (!orientation_ok || !controller_->setNavigation(nav, arrival)) {
    // Throttled: at 10-50 Hz a broken source would flood the log.
    if (bad_odometry_count_++ % 100 == 0) {
      AUV_WARN(node_->logger(),
               "nav/odometry: ignoring an estimate with "
                   << (orientation_ok ? "a non-finite field" : "an invalid orientation quaternion")
                   << " (" << bad_odometry_count_ << " so far); without navigation the "
                   << "NAVIGATION_LOST manoeuvre starts after "
                   << options_.controller.navigation_timeout << " s");
    }
  }
}

void ControllerComponent::onCommand(const msg::ControllerCommand& m) {
  ControlCommand command;
  command.command_id = m.command_id();
  command.mode = static_cast<ControlMode>(static_cast<uint32_t>(m.mode()));
  command.position = {m.position().x(), m.position().y(), m.position().z()};
  command.heading = m.heading();
  command.depth = m.depth();
  command.surge_speed = m.surge_speed();
  command.tolerance = m.tolerance();
  command.timeout = m.timeout();
  command.altitude = m.altitude();
  const CommandResult result = controller_->setCommand(command, node_->clock().nowSeconds());
  switch (result.outcome) {
    case CommandResult::Outcome::ACCEPTED: {
      const ControlCommand& c = controller_->command();
      AUV_INFO(node_->logger(),
               "command " << c.command_id << " " << toString(c.mode) << " (" << c.position.x()
                          << ", " << c.position.y() << ", " << c.position.z() << ") heading "
                          << c.heading << " depth " << c.depth << " speed " << c.surge_speed
                          << " tolerance " << c.tolerance << " timeout " << c.timeout
                          << (c.altitude > 0 ? " altitude " + std::to_string(c.altitude) : ""));
      break;
    }
    case CommandResult::Outcome::REJECTED:
      AUV_ERROR(node_->logger(), "control/waypoint: rejected "
                                     << result.reason << "; keeping command "
                                     << controller_->command().command_id);
      break;
    case CommandResult::Outcome::REFUSED:
      AUV_WARN(node_->logger(), "control/waypoint: " << result.reason);
      break;
    case CommandResult::Outcome::IGNORED:
      AUV_DEBUG(node_->logger(), "control/waypoint: ignored: " << result.reason);
      break;
  }
  reportChanges();
}

void ControllerComponent::controlStep() {
  if (!node_->clock().valid()) return;  // simulation time not started yet
  applyOdometry();
  publishThrusters(controller_->update(node_->clock().nowSeconds()));
  reportChanges();
}

void ControllerComponent::publishThrusters(const ThrusterCommand& command) {
  msg::ThrusterSetpoints setpoints;
  stamp(setpoints.header(), node_->clock(), "base_link");
  setpoints.port(command.port);
  setpoints.starboard(command.starboard);
  setpoints.vertical(command.vertical);
  thrusters_pub_->publish(setpoints);
}

void ControllerComponent::publishStatus() {
  const ControllerStatusReport& s = controller_->status();
  msg::ControllerStatus status;
  stamp(status.header(), node_->clock(), "");
  status.active_command_id(s.active_command_id);
  status.state(static_cast<msg::ControllerState>(s.state));
  status.reached(s.reached);
  status.safety_maneuver(s.safety_maneuver);
  status.safety_reason(static_cast<msg::SafetyReason>(s.safety_reason));
  status.safety_text(s.safety_text);
  status.depth(s.depth);
  status.altitude(s.altitude);
  status.distance_to_target(s.distance_to_target);
  status_pub_->publish(status);
}

void ControllerComponent::reportChanges() {
  const ControllerStatusReport& now = controller_->status();
  const auto& log = node_->logger();
  if (now.safety_maneuver && last_reported_.safety_maneuver &&
      now.safety_reason == last_reported_.safety_reason &&
      now.safety_action != last_reported_.safety_action) {
    // Same manoeuvre, new action (e.g. out from under the rock: ascending now).
    AUV_WARN(log, "safety manoeuvre " << toString(now.safety_reason) << ": " << now.safety_text);
    last_reported_.safety_action = now.safety_action;
    publishStatus();
  }
  if (!now.differsInState(last_reported_)) return;
  if (now.safety_maneuver &&
      (!last_reported_.safety_maneuver || now.safety_reason != last_reported_.safety_reason)) {
    AUV_WARN(log, "safety manoeuvre " << toString(now.safety_reason) << ": " << now.safety_text);
  } else if (!now.safety_maneuver && last_reported_.safety_maneuver) {
    AUV_INFO(log, "safety manoeuvre over; command " << now.active_command_id << " dropped");
  } else if (now.state == ControllerState::FAULT) {
    AUV_WARN(log, "command " << now.active_command_id << " timed out after "
                             << controller_->command().timeout << " s without reaching its goal");
  } else if (now.reached && !last_reported_.reached) {
    AUV_INFO(log, "command " << now.active_command_id << " reached");
  }
  last_reported_ = now;
  publishStatus();
}

}  // namespace auv::control

AUV_REGISTER_COMPONENT(auv::control::ControllerComponent, "controller",
                       "low-level controller: control/waypoint -> control/thrusters")
