#pragma once
// The `mission` component (`auv run mission`): the mission handler of docs/paper.md §2.3 on DDS.
// Subscribes `nav/odometry`, `control/status`, `planner/waypoint`, `planner/cancel`,
// `map/update` (to refuse goals inside known obstacles), and `planner/path` / `planner/tree`
// (only for the mission log); publishes `mission/query`, `planner/waypoint_request`,
// `control/waypoint` and `mission/status` (latched); serves `mission/start` and
// `mission/abort`. All callbacks but the odometry's run on the executor thread, so the
// executive needs no lock; odometry is taken in the middleware thread (see onOdometry).

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "auv/interfaces/component.h"
#include "auv/mapping/map_replica.h"
#include "auv/mission/mission_check.h"
#include "auv/mission/mission_executive.h"
#include "auv/mission/mission_log.h"

namespace auv::mission {

class MissionComponent : public interfaces::Component {
 public:
  struct Options {
    ExecutiveOptions executive;      ///< timeouts and waypoint handling (parameters of that name)
    MissionLimits limits;            ///< max_depth, goal_clearance
    double tick_rate = 10.0;         ///< Hz, readiness / staleness checks
    double status_rate = 1.0;        ///< Hz, periodic mission/status (also sent on changes)
    double map_resolution = 0.5;     ///< m, leaf size of the followed map
    std::string map_id = "octomap";  ///< OctomapUpdate.map_id followed
    std::string mission_file;        ///< mission YAML started on activate() when autostart
    bool autostart = false;
    /// Folder of the mission log (MissionLog); empty = no log.
    std::string log_dir;
    /// The component's own fields with meaning, unit and range; the executive's and the
    /// limits' are in their own tables.
    static const config::OptionTable<Options>& table();
  };

  void configure(interfaces::Node& node) override;
  void activate() override;
  void deactivate() override;
  void cleanup() override;

  /// Current status (executor thread only, e.g. tests spinning the executor themselves).
  const msg::MissionStatus& status() const { return executive_->status(); }

 private:
  /// A mission this launch's handler had running before it restarted (progress.yaml), kept
  /// for the first tick; a progress file that cannot be read is named in the log and ignored.
  void loadProgress();
  /// Resumes the kept mission once the clock runs.
  void resumeMission();
  /// Persists the executive's progress (after every status change); failures are logged.
  void saveProgress();
  /// Validates and starts a mission; throws interfaces::ServiceError with the reason.
  std::string startMission(const std::string& requested_id, const MissionPlan& plan,
                           const std::string& source);
  void onStart(const msg::StartMissionRequest& request, msg::StartMissionReply& reply);
  void onAbort(const msg::TriggerRequest& request, msg::TriggerReply& reply);
  /// Middleware thread: keeps the newest estimate and the time it arrived. Freshness must not
  /// depend on the executor: components composed in one process share its thread, and after a
  /// long callback elsewhere the tick ran before the queued odometry and aborted a mission on
  /// "stale navigation" that had arrived in time (campaigns on a loaded machine).
  void onOdometry(const msg::Odometry& odometry);
  /// Executor thread: hands the newest estimate that arrived to the executive.
  void feedOdometry();
  void tick();
  /// Publishes what the executive produced, logs transitions, closes the log at the end.
  void flush(const std::string& event, const std::string& detail = "");
  void publishStatus();
  double now() const;

  interfaces::Node* node_ = nullptr;
  Options options_;
  std::unique_ptr<MissionExecutive> executive_;
  std::unique_ptr<mapping::MapReplica> map_;
  std::unique_ptr<MissionLog> log_;
  std::optional<MissionPlan> configured_plan_;
  std::optional<MissionProgress> resumable_;  // loaded at configure, resumed on the first tick
  std::string plan_name_;                     // of the running mission (its progress)
  std::string progress_error_;                // the last failed write, logged once
  uint64_t missions_started_ = 0;
  msg::MissionState logged_state_ = msg::MISSION_STATE_IDLE;

  struct LatestOdometry {
    Eigen::Vector3d position = Eigen::Vector3d::Zero();
    double yaw = 0.0;
    double arrival = 0.0;  // s, node clock when it arrived
    uint64_t count = 0;    // estimates received so far
  };
  std::mutex odometry_mutex_;
  LatestOdometry latest_odometry_;   // guarded by odometry_mutex_
  uint64_t fed_odometry_count_ = 0;  // executor thread

  std::shared_ptr<interfaces::Publisher<msg::PlannerQuery>> query_pub_;
  std::shared_ptr<interfaces::Publisher<msg::WaypointRequest>> request_pub_;
  std::shared_ptr<interfaces::Publisher<msg::ControllerCommand>> command_pub_;
  std::shared_ptr<interfaces::Publisher<msg::MissionStatus>> status_pub_;
  std::shared_ptr<interfaces::Subscription<msg::Odometry>> odometry_sub_;
  std::shared_ptr<interfaces::Subscription<msg::ControllerStatus>> controller_sub_;
  std::shared_ptr<interfaces::Subscription<msg::Waypoint>> waypoint_sub_;
  std::shared_ptr<interfaces::Subscription<msg::WaypointCancel>> cancel_sub_;
  std::shared_ptr<interfaces::Subscription<msg::OctomapUpdate>> map_sub_;
  std::shared_ptr<interfaces::Subscription<msg::Path>> path_sub_;
  std::shared_ptr<interfaces::Subscription<msg::PlannerTree>> tree_sub_;
  std::shared_ptr<interfaces::Service<msg::StartMissionRequest, msg::StartMissionReply>>
      start_service_;
  std::shared_ptr<interfaces::Service<msg::TriggerRequest, msg::TriggerReply>> abort_service_;
  std::shared_ptr<interfaces::Timer> tick_timer_;
  std::shared_ptr<interfaces::Timer> status_timer_;
};

}  // namespace auv::mission
