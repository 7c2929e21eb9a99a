// How a mission goes on after an interruption (mission_executive.h): a controller safety
// manoeuvre or a silent controller (RECOVERING), a planner that lost the query (re-issued), a
// handler restarted within the launch (resume from MissionProgress).
#include <algorithm>
#include <cmath>

#include "auv/mission/executive_text.h"
#include "auv/mission/mission_executive.h"

namespace auv::mission {
namespace {

const char* reasonName(msg::SafetyReason reason) {
  static const char* const kNames[] = {
      "NONE",        "MIN_ALTITUDE", "MAX_DEPTH",       "OBSTACLE", "NAVIGATION_LOST",
      "LOW_BATTERY", "LEAK",         "COMMAND_TIMEOUT", "OPERATOR", "OTHER"};
  const auto index = static_cast<size_t>(reason);
  return index < sizeof(kNames) / sizeof(kNames[0]) ? kNames[index] : "UNKNOWN";
}

// Manoeuvres a re-issued query cannot help with: the vehicle must come home or be looked at.
bool abortsAtOnce(msg::SafetyReason reason) {
  return reason == msg::SAFETY_REASON_OPERATOR || reason == msg::SAFETY_REASON_LEAK ||
         reason == msg::SAFETY_REASON_LOW_BATTERY;
}

}  // namespace

bool MissionExecutive::resume(const MissionProgress& progress, double now, std::string* why) {
  if (running()) {
    *why = "mission '" + status_.mission_id() + "' is " + toString(status_.state());
    return false;
  }
  if (!progress.running()) {
    *why = "mission '" + progress.mission_id + "' had ended (" + toString(progress.state) + ")";
    return false;
  }
  const auto count = static_cast<int32_t>(progress.plan.queries.size());
  if (progress.query_index < 0 || progress.query_index >= count) {
    *why = "query index " + std::to_string(progress.query_index) + " is not one of the " +
           std::to_string(count) + " queries";
    return false;
  }
  queries_ = progress.plan.queries;
  mission_depth_ = progress.mission_depth;
  msg::MissionStatus resumed;
  resumed.mission_id(progress.mission_id);
  resumed.start_time().sec(static_cast<int32_t>(std::floor(progress.start_time)));
  resumed.start_time().nanosec(
      static_cast<uint32_t>((progress.start_time - std::floor(progress.start_time)) * 1e9));
  resumed.current_query_index(progress.query_index);
  resumed.query_count(static_cast<uint32_t>(count));
  resumed.queries_succeeded(progress.queries_succeeded);
  resumed.queries_failed(progress.queries_failed);
  resumed.waypoints_received(progress.waypoints_received);
  resumed.waypoints_reached(progress.waypoints_reached);
  resumed.waypoints_cancelled(progress.waypoints_cancelled);
  resumed.recoveries(progress.recoveries);
  status_ = resumed;
  next_query_id_ = std::max(next_query_id_, progress.next_query_id);
  next_command_id_ = std::max(next_command_id_, progress.next_command_id);
  query_recoveries_ = progress.query_recoveries;
  current_.reset();
  next_.reset();
  command_id_ = 0;
  holding_since_.reset();
  readiness_since_ = now;
  outbox_.events.push_back({"RESUMED", "mission '" + progress.mission_id + "' resumed at query " +
                                           std::to_string(progress.query_index + 1) + "/" +
                                           std::to_string(count) + " (was " +
                                           toString(progress.state) + ")"});
  setState(msg::MISSION_STATE_CHECKING_READINESS, "resumed after a restart: checking readiness");
  tick(now);
  return true;
}

MissionProgress MissionExecutive::progress() const {
  MissionProgress p;
  p.mission_id = status_.mission_id();
  p.plan.queries = queries_;
  p.state = status_.state();
  p.query_index = status_.current_query_index();
  p.start_time = status_.start_time().sec() + 1e-9 * status_.start_time().nanosec();
  p.queries_succeeded = status_.queries_succeeded();
  p.queries_failed = status_.queries_failed();
  p.waypoints_received = status_.waypoints_received();
  p.waypoints_reached = status_.waypoints_reached();
  p.waypoints_cancelled = status_.waypoints_cancelled();
  p.recoveries = status_.recoveries();
  p.query_recoveries = query_recoveries_;
  p.next_query_id = next_query_id_;
  p.next_command_id = next_command_id_;
  p.mission_depth = mission_depth_;
  return p;
}

void MissionExecutive::reissueLostQuery(const msg::WaypointCancel& cancel, double now) {
  // The planner restarted (or lost the query): stop where we are and give it the query again
  // from here. Progress made (EXECUTING) restarts the no-solution clock; a planner that keeps
  // failing before its first waypoint does not: it still aborts after no_solution_timeout.
  const bool progressed = status_.state() == msg::MISSION_STATE_EXECUTING;
  const double waiting_since = waiting_since_;
  const uint64_t old_query = status_.current_query_id();
  hold(true);
  startQuery(now);
  if (!progressed) waiting_since_ = waiting_since;
  const std::string detail = "query " + std::to_string(status_.current_query_index() + 1) +
                             " re-issued as query id " +
                             std::to_string(status_.current_query_id()) + " (was " +
                             std::to_string(old_query) + "): " + cancel.reason_text();
  outbox_.events.push_back({"PLANNER_REISSUE", detail});
  setState(msg::MISSION_STATE_WAITING_FOR_WAYPOINT, detail + "; waiting for the first waypoint");
}

void MissionExecutive::startRecovery(const msg::ControllerStatus& status, double now) {
  const std::string cause =
      std::string(reasonName(status.safety_reason())) + ": " + status.safety_text();
  if (abortsAtOnce(status.safety_reason())) {
    current_.reset();
    next_.reset();
    command_id_ = 0;
    setState(msg::MISSION_STATE_ABORTED,
             "controller safety manoeuvre " + cause +
                 " (the controller keeps the vehicle safe; restart the mission when clear)");
    return;
  }
  beginRecovery(cause, "controller safety manoeuvre " + cause, now);
}

void MissionExecutive::beginRecovery(const std::string& cause, const std::string& interruption,
                                     double now) {
  const auto limit = static_cast<uint32_t>(options_.max_recoveries);
  current_.reset();
  next_.reset();
  command_id_ = 0;
  if (query_recoveries_ >= limit) {
    setState(msg::MISSION_STATE_ABORTED,
             interruption + "; recoveries exhausted (" + std::to_string(query_recoveries_) +
                 " of max_recoveries " + std::to_string(limit) +
                 " used by this query) (the controller keeps the vehicle safe; restart the "
                 "mission when clear)");
    return;
  }
  ++query_recoveries_;
  status_.recoveries(status_.recoveries() + 1);
  recovery_since_ = now;
  holding_since_.reset();
  recovery_cause_ = cause;
  next_requested_ = false;
  const std::string detail = "recovery " + std::to_string(query_recoveries_) + "/" +
                             std::to_string(limit) + " of query " +
                             std::to_string(status_.current_query_index() + 1) + " after " + cause;
  outbox_.events.push_back({"RECOVERY_START", detail});
  // The controller refuses commands during its manoeuvre: nothing is sent until it is over.
  setState(msg::MISSION_STATE_RECOVERING, detail + "; waiting for the manoeuvre to end");
}

void MissionExecutive::continueRecovery(double now) {
  const bool controller = now - controller_time_ <= options_.controller_timeout;
  if (!controller) holding_since_.reset();  // the hold was not heard: send it again later
  const bool manoeuvre = controller_ && controller_->safety_maneuver();
  const bool navigation = position_ && now - odometry_time_ <= options_.odometry_timeout;
  if (!holding_since_ && (!controller || manoeuvre || !navigation)) {
    if (now - recovery_since_ > options_.recovery_timeout) {
      const std::string what = !controller ? std::string("a silent controller")
                               : manoeuvre ? "the safety manoeuvre (" + recovery_cause_ + ")"
                                           : std::string("stale navigation");
      abortToHold("recovery given up: " + what + " still on after " +
                  formatSeconds(now - recovery_since_) + " (recovery_timeout " +
                  formatSeconds(options_.recovery_timeout) + ")");
    }
    return;
  }
  if (!holding_since_) {
    // Over: hold where the controller left the vehicle while the map takes in the cause.
    holding_since_ = now;
    hold(true);
    setState(msg::MISSION_STATE_RECOVERING, "manoeuvre over (" + recovery_cause_ + "); holding " +
                                                formatSeconds(options_.recovery_hold) +
                                                " before re-issuing query " +
                                                std::to_string(status_.current_query_index() + 1));
    return;
  }
  if (now - *holding_since_ < options_.recovery_hold) return;
  if (!navigation) return;  // the query starts from the vehicle's position: wait for it
  const uint64_t old_query = status_.current_query_id();
  holding_since_.reset();
  startQuery(now);
  const std::string detail =
      "query " + std::to_string(status_.current_query_index() + 1) + " re-issued as query id " +
      std::to_string(status_.current_query_id()) + " (was " + std::to_string(old_query) +
      "), recovery " + std::to_string(query_recoveries_) + " after " + recovery_cause_;
  outbox_.events.push_back({"RECOVERY_REISSUE", detail});
  setState(msg::MISSION_STATE_WAITING_FOR_WAYPOINT, detail + "; waiting for the first waypoint");
}

}  // namespace auv::mission
