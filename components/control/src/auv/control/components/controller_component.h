#pragma once
// The vehicle's low-level controller as a component (`auv run controller`): LowLevelController
// on DDS. Subscribes `control/waypoint` (ControllerCommand) and `nav/odometry` (Odometry);
// publishes `control/thrusters` (ThrusterSetpoints) at control_rate and `control/status`
// (ControllerStatus) at status_rate and on every change of state. Runs on the node clock, so
// `use_sim_time` makes it follow the simulator. Keeps a replica of the map (`map/update`), off
// the control thread (MapFollower), to tell the safety manoeuvres whether the water above the
// vehicle is open (overheadClearance).

#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "auv/control/components/map_follower.h"
#include "auv/control/controller.h"
#include "auv/interfaces/component.h"

namespace auv::control {

class ControllerComponent : public interfaces::Component {
 public:
  struct Options {
    double control_rate = 20.0;      ///< Hz, control steps and `control/thrusters` messages
    double status_rate = 2.0;        ///< Hz, periodic `control/status` (also sent on changes)
    std::string map_id = "octomap";  ///< OctomapUpdate.map_id followed
    double map_resolution = 0.5;     ///< m, leaf size of the followed map
    /// m, radius of the water column above the vehicle that must be free of known rock for a
    /// safety manoeuvre to ascend: the hull radius (0.8) plus a margin, below the planner's
    /// clearance (1.2) so that a wall it keeps that far from does not count as rock above.
    double overhead_radius = 1.0;
    ControllerOptions controller;  ///< parameters `controller.*` (model: `controller.model.*`)
    /// The component's own fields (the rates) with meaning, unit and range; the controller's
    /// are in ControllerOptions::table().
    static const config::OptionTable<Options>& table();
  };

  /// Declares and checks the parameters (ParameterError or ConfigError naming the parameter)
  /// and creates the publishers and subscriptions.
  void configure(interfaces::Node& node) override;
  /// Starts the control and status timers.
  void activate() override;
  /// Stops the timers and sends one all-stop setpoint.
  void deactivate() override;
  void cleanup() override;

  /// The controller's current status (call from the executor's thread, e.g. in tests).
  const ControllerStatusReport& status() const { return controller_->status(); }
  const Options& options() const { return options_; }

  /// Distance from `position` up to the deep face of the nearest occupied cell of `map` wholly
  /// above it whose centre lies within `radius` (horizontally), up to the surface (z = 0, NED);
  /// +infinity when none. Unknown cells count as open (the paper's assumption).
  static double overheadClearance(const octomap::OcTree& map, const Eigen::Vector3d& position,
                                  double radius);

 private:
  /// Middleware thread: keeps the newest estimate with its arrival time. Navigation age must
  /// not depend on the executor: components composed in one process share its thread, and
  /// after a long callback elsewhere the control step ran before the queued odometry and saw
  /// navigation older than it was (mission campaigns on a loaded machine).
  void onOdometry(const msg::Odometry& odometry);
  /// Executor thread: hands the newest estimate that arrived to the controller.
  void applyOdometry();
  void onCommand(const msg::ControllerCommand& command);
  void controlStep();
  void publishThrusters(const ThrusterCommand& command);
  void publishStatus();
  /// Publishes the status at once when its state changed, and logs the transition.
  void reportChanges();

  interfaces::Node* node_ = nullptr;
  Options options_;
  std::unique_ptr<LowLevelController> controller_;
  ControllerStatusReport last_reported_;
  int64_t bad_odometry_count_ = 0;  // for throttled warnings
  std::mutex odometry_mutex_;
  std::optional<msg::Odometry> latest_odometry_;  // guarded by odometry_mutex_
  double latest_odometry_arrival_ = 0.0;          // s, node clock; guarded by odometry_mutex_

  std::shared_ptr<interfaces::Subscription<msg::ControllerCommand>> command_sub_;
  std::shared_ptr<interfaces::Subscription<msg::Odometry>> odometry_sub_;
  std::shared_ptr<interfaces::Subscription<msg::OctomapUpdate>> map_sub_;
  std::unique_ptr<MapFollower> map_;
  double last_overhead_clearance_ = std::numeric_limits<double>::quiet_NaN();  // probe's answer
  std::shared_ptr<interfaces::Publisher<msg::ThrusterSetpoints>> thrusters_pub_;
  std::shared_ptr<interfaces::Publisher<msg::ControllerStatus>> status_pub_;
  std::shared_ptr<interfaces::Timer> control_timer_;
  std::shared_ptr<interfaces::Timer> status_timer_;
};

}  // namespace auv::control
