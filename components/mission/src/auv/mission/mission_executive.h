#pragma once
// The mission handler's logic (docs/paper.md §2.3), without DDS: a state machine fed with the
// vehicle's navigation, the controller's status and the planner's waypoints and cancels, that
// emits planner queries, waypoint requests and controller commands into an outbox. The
// `mission` component wires it to topics; tests drive it directly with a clock of their own.
//
//   IDLE --start--> CHECKING_READINESS --ready--> WAITING_FOR_WAYPOINT <--cancel-- EXECUTING
//                                                  --waypoint--> EXECUTING --goal--> next query
//   any active state --no waypoint for too long / abort--> ABORTED (hold)
//   WAITING_FOR_WAYPOINT / EXECUTING --controller safety manoeuvre--> RECOVERING: wait for the
//     manoeuvre to end (the controller keeps the vehicle safe), HOLD recovery_hold s (the map
//     takes in what caused it), re-issue the query from where the vehicle is (new query id)
//     --> WAITING_FOR_WAYPOINT. At most max_recoveries per query; ABORTED when they are used up,
//     when the manoeuvre (or stale navigation after it) lasts past recovery_timeout, or on abort.
//     Manoeuvres for OPERATOR, LEAK and LOW_BATTERY abort at once (nothing to retry). A
//     controller silent past controller_timeout (its process restarting), and navigation
//     stale past odometry_timeout (after a depth hold), are recovered alike.
//   WAITING_FOR_WAYPOINT / EXECUTING --cancel UNKNOWN_QUERY (the planner restarted)--> hold,
//     re-issue the query from where the vehicle is --> WAITING_FOR_WAYPOINT.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "auv/config/option_table.h"
#include "auv/mission/mission_plan.h"
#include "auv/mission/mission_progress.h"
#include "auv/msg/all.h"

namespace auv::mission {

struct ExecutiveOptions {
  /// s, navigation older than this is stale: not ready, or abort to hold while running.
  double odometry_timeout = 1.0;
  /// s, a controller status older than this counts as no controller (not ready).
  double controller_timeout = 5.0;
  /// s, a started mission that is not ready within this long fails.
  double readiness_timeout = 60.0;
  /// s, waiting this long for a waypoint (the planner finds nothing) aborts to hold.
  double no_solution_timeout = 60.0;
  /// m, the next waypoint is requested when the vehicle is this close to the current one, so
  /// it is ready on arrival (0: request on arrival only).
  double request_distance = 1.5;
  /// s, an unanswered waypoint request is repeated this often (a lost message, a restarted
  /// planner).
  double request_period = 2.0;
  /// Controller command timeout = factor × distance / speed + waypoint_timeout_margin.
  double waypoint_timeout_factor = 4.0;
  double waypoint_timeout_margin = 30.0;  ///< s
  /// Re-issues of one query after controller safety manoeuvres (0: a manoeuvre aborts).
  double max_recoveries = 3;
  /// s, held after a manoeuvre before the query is re-issued (the map takes in the cause).
  double recovery_hold = 5.0;
  /// s, a recovery whose manoeuvre has not ended (or navigation not returned) this long after
  /// it began aborts the mission.
  double recovery_timeout = 180.0;
  /// The fields with meaning, unit and range (the mission component's parameters of those
  /// names).
  static const config::OptionTable<ExecutiveOptions>& table();
  /// Throws std::invalid_argument naming the field.
  void check() const;
};

class MissionExecutive {
 public:
  /// What the component must send, in order.
  struct Outbox {
    std::vector<msg::PlannerQuery> queries;
    std::vector<msg::WaypointRequest> requests;
    std::vector<msg::ControllerCommand> commands;
    /// Named events for the mission log (RECOVERY_START, RECOVERY_REISSUE) with their detail.
    struct Event {
      std::string name;
      std::string detail;
    };
    std::vector<Event> events;
    bool status_changed = false;
  };

  explicit MissionExecutive(const ExecutiveOptions& options);

  /// Starts `queries` as mission `mission_id` at time `now` (s). False, with the reason in
  /// `why`, when a mission is already running.
  bool start(const std::string& mission_id, const std::vector<MissionQuery>& queries, double now,
             std::string* why);
  /// Goes on with a mission a handler had running before it restarted: CHECKING_READINESS,
  /// then the query in progress is issued again from where the vehicle is, with new ids and
  /// the recoveries it had used. False, with the reason in `why`, when a mission is running or
  /// `progress` has none to resume.
  bool resume(const MissionProgress& progress, double now, std::string* why);
  /// What resume() needs (plan name and launch id left to the caller).
  MissionProgress progress() const;
  /// Stops the running mission (ABORTED) and holds the vehicle (no command while still checking
  /// readiness: the mission has not commanded it). False when none is running.
  bool abort(const std::string& reason, double now);

  void onOdometry(const Eigen::Vector3d& position, double yaw, double now);
  void onControllerStatus(const msg::ControllerStatus& status, double now);
  void onWaypoint(const msg::Waypoint& waypoint, double now);
  void onCancel(const msg::WaypointCancel& cancel, double now);
  /// Whether a planner listens to the queries (checked for readiness).
  void setPlannerPresent(bool present) { planner_present_ = present; }
  /// Time-driven checks: readiness, stale navigation, waiting too long, repeated requests.
  void tick(double now);

  Outbox takeOutbox();
  /// The status (stamp left to the caller).
  const msg::MissionStatus& status() const { return status_; }
  bool running() const;
  /// Why the vehicle is not ready now (empty when it is).
  std::string notReadyReason(double now) const;
  const std::optional<Eigen::Vector3d>& vehiclePosition() const { return position_; }

 private:
  void setState(msg::MissionState state, const std::string& message);
  void startQuery(double now);
  void requestWaypoint(uint64_t reached_waypoint_id, double now);
  void command(const msg::Waypoint& waypoint);
  void waypointReached(double now);
  void finishQuery(bool succeeded, double now);
  /// The planner has no such query (CANCEL_REASON_UNKNOWN_QUERY): hold, re-issue it from here.
  void reissueLostQuery(const msg::WaypointCancel& cancel, double now);
  /// HOLD at the current position, or (keep_position false) a speed-0 setpoint at the current
  /// depth and heading.
  void hold(bool keep_position);
  void abortToHold(const std::string& reason);
  /// A safety manoeuvre interrupted the query: RECOVERING, or ABORTED when it may not.
  void startRecovery(const msg::ControllerStatus& status, double now);
  /// RECOVERING after `cause` (a manoeuvre's reason, a silent controller), or ABORTED, saying
  /// `interruption`, when this query's recoveries are used up.
  void beginRecovery(const std::string& cause, const std::string& interruption, double now);
  /// RECOVERING: hold once the manoeuvre is over, re-issue after recovery_hold, or give up.
  void continueRecovery(double now);

  ExecutiveOptions options_;
  msg::MissionStatus status_;
  Outbox outbox_;
  std::vector<MissionQuery> queries_;
  double readiness_since_ = 0.0;

  std::optional<Eigen::Vector3d> position_;
  double yaw_ = 0.0;
  double odometry_time_ = -1e300;
  std::optional<msg::ControllerStatus> controller_;
  double controller_time_ = -1e300;
  bool planner_present_ = false;

  uint64_t next_query_id_ = 1;
  uint64_t next_command_id_ = 1;
  uint64_t command_id_ = 0;  // controller command following the current waypoint
  std::optional<msg::Waypoint> current_;
  std::optional<msg::Waypoint> next_;
  Eigen::Vector3d goal_{0, 0, 0};
  std::optional<double> mission_depth_;  // plane of fixed-depth queries that give no depth
  double goal_tolerance_ = 0.0;
  bool next_requested_ = false;
  double waiting_since_ = 0.0;
  double last_request_time_ = 0.0;
  uint64_t last_request_reached_id_ = 0;

  // Recovery after a safety manoeuvre.
  uint32_t query_recoveries_ = 0;        // recoveries of the current query (status: whole mission)
  double recovery_since_ = 0.0;          // s, when the manoeuvre interrupted the query
  std::optional<double> holding_since_;  // s, manoeuvre over, HOLD sent
  std::string recovery_cause_;           // the manoeuvre's reason and text
  std::optional<double> commandless_since_;  // s, EXECUTING and the controller reports no command
};

const char* toString(msg::MissionState state);

}  // namespace auv::mission
