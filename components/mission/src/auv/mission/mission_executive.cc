#include "auv/mission/mission_executive.h"
#include "auv/interfaces/msg_eigen.h"
#include "auv/mission/executive_text.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace auv::mission {
namespace {

Eigen::Vector3d toVector(const msg::Point& p) { return interfaces::toEigen(p); }
using interfaces::toPoint;

}  // namespace

const char* toString(msg::MissionState state) {
  switch (state) {
    case msg::MISSION_STATE_IDLE:
      return "IDLE";
    case msg::MISSION_STATE_CHECKING_READINESS:
      return "CHECKING_READINESS";
    case msg::MISSION_STATE_WAITING_FOR_WAYPOINT:
      return "WAITING_FOR_WAYPOINT";
    case msg::MISSION_STATE_EXECUTING:
      return "EXECUTING";
    case msg::MISSION_STATE_SUCCEEDED:
      return "SUCCEEDED";
    case msg::MISSION_STATE_FAILED:
      return "FAILED";
    case msg::MISSION_STATE_ABORTED:
      return "ABORTED";
    case msg::MISSION_STATE_RECOVERING:
      return "RECOVERING";
    default:
      return "UNKNOWN";
  }
}

const config::OptionTable<ExecutiveOptions>& ExecutiveOptions::table() {
  using config::Range;
  using O = ExecutiveOptions;
  static const config::OptionTable<O> kTable = {
      {"odometry_timeout", &O::odometry_timeout,
       "nav/odometry older than this is stale: not ready; while running a depth hold and a "
       "recovery",
       "s", Range::above(0)},
      {"controller_timeout", &O::controller_timeout,
       "control/status older than this counts as no controller (not ready; while running a "
       "recovery)",
       "s", Range::above(0)},
      {"readiness_timeout", &O::readiness_timeout,
       "a started mission that is not ready within this long fails", "s", Range::above(0)},
      {"no_solution_timeout", &O::no_solution_timeout,
       "waiting this long for a waypoint (the planner finds nothing) aborts to hold", "s",
       Range::above(0)},
      {"request_period", &O::request_period,
       "an unanswered waypoint request is repeated this often", "s", Range::above(0)},
      {"waypoint_timeout_margin", &O::waypoint_timeout_margin,
       "controller command timeout = factor x distance / speed + this margin", "s",
       Range::atLeast(0)},
      {"request_distance", &O::request_distance,
       "ask for the next waypoint this close to the current one (0: on arrival)", "m",
       Range::closed(0.0, 100.0)},
      {"waypoint_timeout_factor", &O::waypoint_timeout_factor,
       "controller command timeout = this x distance / speed + margin", "",
       Range::aboveUpTo(0.0, 100.0)},
      {"max_recoveries", &O::max_recoveries,
       "re-issues of one query after controller safety manoeuvres (0: a manoeuvre aborts)", "",
       Range::closed(0.0, 100.0)},
      {"recovery_hold", &O::recovery_hold,
       "held after a safety manoeuvre before the query is re-issued from where the vehicle is", "s",
       Range::closed(0.0, 600.0)},
      {"recovery_timeout", &O::recovery_timeout,
       "a recovery whose safety manoeuvre has not ended this long after it began aborts", "s",
       Range::above(0)},
  };
  return kTable;
}

void ExecutiveOptions::check() const {
  config::checkOptions(*this, table());
  if (max_recoveries != std::floor(max_recoveries)) {
    std::ostringstream got;
    got << max_recoveries;
    throw std::invalid_argument("max_recoveries: must be a whole number, got " + got.str());
  }
}

MissionExecutive::MissionExecutive(const ExecutiveOptions& options) : options_(options) {
  options_.check();
  status_.state(msg::MISSION_STATE_IDLE);
  status_.current_query_index(-1);
  status_.message("no mission");
}

bool MissionExecutive::running() const { return isRunning(status_.state()); }

void MissionExecutive::setState(msg::MissionState state, const std::string& message) {
  status_.state(state);
  status_.message(message);
  outbox_.status_changed = true;
}

MissionExecutive::Outbox MissionExecutive::takeOutbox() {
  Outbox out;
  std::swap(out, outbox_);
  return out;
}

bool MissionExecutive::start(const std::string& mission_id,
                             const std::vector<MissionQuery>& queries, double now,
                             std::string* why) {
  if (running()) {
    *why = "mission '" + status_.mission_id() + "' is " + toString(status_.state());
    return false;
  }
  if (queries.empty()) {
    *why = "the mission has no queries";
    return false;
  }
  queries_ = queries;
  mission_depth_.reset();
  msg::MissionStatus fresh;
  fresh.mission_id(mission_id);
  fresh.start_time().sec(static_cast<int32_t>(std::floor(now)));
  fresh.start_time().nanosec(static_cast<uint32_t>((now - std::floor(now)) * 1e9));
  fresh.current_query_index(0);
  fresh.query_count(static_cast<uint32_t>(queries.size()));
  status_ = fresh;
  current_.reset();
  next_.reset();
  query_recoveries_ = 0;
  holding_since_.reset();
  readiness_since_ = now;
  setState(msg::MISSION_STATE_CHECKING_READINESS, "checking readiness");
  tick(now);
  return true;
}

std::string MissionExecutive::notReadyReason(double now) const {
  if (!position_) return "no navigation (nav/odometry) received";
  if (now - odometry_time_ > options_.odometry_timeout) {
    // Fixed wording: a message that changed every tick would republish the status each tick.
    return "navigation stale (no nav/odometry within odometry_timeout " +
           formatSeconds(options_.odometry_timeout) + ")";
  }
  if (!controller_ || now - controller_time_ > options_.controller_timeout) {
    return "no controller status (control/status) within " +
           formatSeconds(options_.controller_timeout);
  }
  if (controller_->safety_maneuver()) {
    return "controller in a safety manoeuvre: " + controller_->safety_text();
  }
  if (!planner_present_) return "no planner subscribed to mission/query";
  return "";
}

void MissionExecutive::tick(double now) {
  const auto state = status_.state();
  if (state == msg::MISSION_STATE_CHECKING_READINESS) {
    const std::string reason = notReadyReason(now);
    if (reason.empty()) {
      startQuery(now);
    } else if (now - readiness_since_ > options_.readiness_timeout) {
      setState(msg::MISSION_STATE_FAILED,
               "not ready after " + formatSeconds(options_.readiness_timeout) + ": " + reason);
    } else if (status_.message() != "not ready: " + reason) {
      setState(state, "not ready: " + reason);
    }
    return;
  }
  if (state == msg::MISSION_STATE_RECOVERING) {
    continueRecovery(now);
    return;
  }
  if (state != msg::MISSION_STATE_WAITING_FOR_WAYPOINT && state != msg::MISSION_STATE_EXECUTING) {
    return;
  }
  if (now - odometry_time_ > options_.odometry_timeout) {
    // Stop where we are on depth and heading alone (safe without navigation), then wait for
    // navigation to return as in any recovery: a dropout that clears does not end the mission.
    hold(false);
    const std::string cause = "navigation stale: last nav/odometry " +
                              formatSeconds(now - odometry_time_) + " ago (odometry_timeout " +
                              formatSeconds(options_.odometry_timeout) + "); holding depth";
    beginRecovery(cause, cause, now);
    return;
  }
  if (now - controller_time_ > options_.controller_timeout) {
    // Its process may be restarting: the recovery waits for it (up to recovery_timeout).
    const std::string cause = "controller silent: no control/status for " +
                              formatSeconds(now - controller_time_) + " (controller_timeout " +
                              formatSeconds(options_.controller_timeout) + ")";
    beginRecovery(cause, cause, now);
    return;
  }
  if (state == msg::MISSION_STATE_WAITING_FOR_WAYPOINT) {
    if (now - waiting_since_ > options_.no_solution_timeout) {
      abortToHold("no waypoint from the planner for " + formatSeconds(now - waiting_since_) +
                  " (no_solution_timeout)");
      return;
    }
    if (now - last_request_time_ >= options_.request_period) {
      requestWaypoint(last_request_reached_id_, now);
    }
  }
}

void MissionExecutive::startQuery(double now) {
  const std::size_t index = static_cast<std::size_t>(status_.current_query_index());
  const MissionQuery& q = queries_[index];
  msg::PlannerQuery query = toPlannerQuery(q);
  query.query_id(next_query_id_++);
  query.start().position(toPoint(*position_));
  query.start().orientation().w(std::cos(yaw_ / 2));
  query.start().orientation().z(std::sin(yaw_ / 2));
  if (q.fixed_depth && !q.depth) {
    // The vehicle's depth when the mission's first such query starts, kept for the others:
    // each query re-reading it would let the plane creep with every hold.
    if (!mission_depth_) mission_depth_ = position_->z();
    query.depth(*mission_depth_);
  }
  goal_ = q.goal;
  if (query.fixed_depth()) goal_.z() = query.depth();
  goal_tolerance_ = q.goal_tolerance;
  outbox_.queries.push_back(query);
  status_.current_query_id(query.query_id());
  status_.current_waypoint_id(0);
  current_.reset();
  next_.reset();
  next_requested_ = false;
  waiting_since_ = now;
  setState(msg::MISSION_STATE_WAITING_FOR_WAYPOINT,
           "query " + std::to_string(index + 1) + "/" + std::to_string(queries_.size()) + " '" +
               q.name + "': waiting for the first waypoint");
  requestWaypoint(0, now);
}

void MissionExecutive::requestWaypoint(uint64_t reached_waypoint_id, double now) {
  msg::WaypointRequest request;
  request.query_id(status_.current_query_id());
  request.reached_waypoint_id(reached_waypoint_id);
  outbox_.requests.push_back(request);
  last_request_time_ = now;
  last_request_reached_id_ = reached_waypoint_id;
}

void MissionExecutive::onOdometry(const Eigen::Vector3d& position, double yaw, double now) {
  position_ = position;
  yaw_ = yaw;
  odometry_time_ = now;
  if (status_.state() != msg::MISSION_STATE_EXECUTING || !current_) return;
  const double distance = (position - toVector(current_->position())).norm();
  if (distance <= current_->tolerance()) {
    waypointReached(now);
  } else if (!next_requested_ && !current_->is_final() && distance <= options_.request_distance) {
    next_requested_ = true;  // ask early so the next waypoint is there on arrival
    requestWaypoint(current_->waypoint_id(), now);
  }
}

void MissionExecutive::onControllerStatus(const msg::ControllerStatus& status, double now) {
  controller_ = status;
  controller_time_ = now;
  if (!running()) return;
  if (status_.state() == msg::MISSION_STATE_RECOVERING) {
    if (status.safety_maneuver()) holding_since_.reset();  // again: wait for it to end
    continueRecovery(now);
    return;
  }
  if (status.safety_maneuver() && status_.state() != msg::MISSION_STATE_CHECKING_READINESS) {
    startRecovery(status, now);
    return;
  }
  if (status_.state() == msg::MISSION_STATE_EXECUTING && status.reached() &&
      status.active_command_id() == command_id_ && command_id_ != 0) {
    waypointReached(now);
    return;
  }
  // A controller that restarted faster than controller_timeout reports no command at all: it
  // holds nothing and drives nowhere, so the waypoint would never be reached.
  const bool commandless = status_.state() == msg::MISSION_STATE_EXECUTING && command_id_ != 0 &&
                           status.active_command_id() == 0;
  if (!commandless) {
    commandless_since_.reset();
  } else if (!commandless_since_) {
    commandless_since_ = now;  // the command may still be on its way
  } else if (now - *commandless_since_ > options_.controller_timeout) {
    const std::string cause =
        "the controller has lost command " + std::to_string(command_id_) + " (restarted?)";
    commandless_since_.reset();
    beginRecovery(cause, cause, now);
  }
}

void MissionExecutive::onWaypoint(const msg::Waypoint& waypoint, double now) {
  const auto state = status_.state();
  if (state != msg::MISSION_STATE_WAITING_FOR_WAYPOINT && state != msg::MISSION_STATE_EXECUTING) {
    return;  // not asked for (a recovery re-issues the query: its waypoints are stale)
  }
  if (waypoint.query_id() != status_.current_query_id()) return;
  if ((current_ && waypoint.waypoint_id() == current_->waypoint_id()) ||
      (next_ && waypoint.waypoint_id() == next_->waypoint_id())) {
    return;  // a repeat
  }
  status_.waypoints_received(status_.waypoints_received() + 1);
  if (status_.state() == msg::MISSION_STATE_WAITING_FOR_WAYPOINT) {
    command(waypoint);
    setState(msg::MISSION_STATE_EXECUTING,
             "query " + std::to_string(status_.current_query_index() + 1) + "/" +
                 std::to_string(queries_.size()) + ": waypoint " +
                 std::to_string(waypoint.waypoint_id()));
    (void)now;
  } else if (status_.state() == msg::MISSION_STATE_EXECUTING) {
    next_ = waypoint;  // commanded when the current one is reached
    outbox_.status_changed = true;
  }
}

void MissionExecutive::command(const msg::Waypoint& waypoint) {
  current_ = waypoint;
  next_requested_ = false;
  command_id_ = next_command_id_++;
  status_.current_waypoint_id(waypoint.waypoint_id());
  msg::ControllerCommand command;
  command.header().frame_id("world");
  command.command_id(command_id_);
  command.mode(msg::CONTROL_MODE_WAYPOINT);
  command.position(waypoint.position());
  command.heading(waypoint.heading());
  command.depth(waypoint.position().z());
  command.surge_speed(waypoint.speed());
  command.tolerance(waypoint.tolerance());
  const double distance = position_ ? (toVector(waypoint.position()) - *position_).norm() : 0.0;
  command.timeout(options_.waypoint_timeout_factor * distance / std::max(waypoint.speed(), 0.01) +
                  options_.waypoint_timeout_margin);
  outbox_.commands.push_back(command);
}

void MissionExecutive::waypointReached(double now) {
  status_.waypoints_reached(status_.waypoints_reached() + 1);
  const bool at_goal = position_ && (*position_ - goal_).norm() <= goal_tolerance_;
  if (current_->is_final() || at_goal) {
    finishQuery(true, now);
    return;
  }
  const uint64_t reached = current_->waypoint_id();
  if (next_) {
    const msg::Waypoint next = *next_;
    next_.reset();
    command(next);
    setState(msg::MISSION_STATE_EXECUTING, "query " +
                                               std::to_string(status_.current_query_index() + 1) +
                                               "/" + std::to_string(queries_.size()) +
                                               ": waypoint " + std::to_string(next.waypoint_id()));
    return;
  }
  current_.reset();
  command_id_ = 0;
  waiting_since_ = now;
  setState(msg::MISSION_STATE_WAITING_FOR_WAYPOINT,
           "waypoint " + std::to_string(reached) + " reached; waiting for the next");
  // The controller keeps the reached waypoint; the early request may already be in flight.
  if (!next_requested_) requestWaypoint(reached, now);
  next_requested_ = false;
}

void MissionExecutive::finishQuery(bool succeeded, double now) {
  if (succeeded) status_.queries_succeeded(status_.queries_succeeded() + 1);
  current_.reset();
  next_.reset();
  command_id_ = 0;
  const int32_t next_index = status_.current_query_index() + 1;
  if (next_index >= static_cast<int32_t>(queries_.size())) {
    status_.current_query_index(-1);
    status_.current_query_id(0);
    status_.current_waypoint_id(0);
    hold(true);
    setState(msg::MISSION_STATE_SUCCEEDED,
             "all " + std::to_string(queries_.size()) + " queries reached their goals");
    return;
  }
  status_.current_query_index(next_index);
  query_recoveries_ = 0;
  startQuery(now);
}

void MissionExecutive::onCancel(const msg::WaypointCancel& cancel, double now) {
  const auto state = status_.state();
  if (state != msg::MISSION_STATE_WAITING_FOR_WAYPOINT && state != msg::MISSION_STATE_EXECUTING) {
    return;  // nothing followed (a recovery re-issues the query anyway)
  }
  if (cancel.query_id() != status_.current_query_id()) return;
  const uint64_t id = cancel.waypoint_id();
  const bool ours = id == 0 || (current_ && id == current_->waypoint_id()) ||
                    (next_ && id == next_->waypoint_id());
  if (!ours) return;
  status_.waypoints_cancelled(status_.waypoints_cancelled() + 1);
  if (cancel.reason() == msg::CANCEL_REASON_NO_SOLUTION) {
    abortToHold("planner found no solution: " + cancel.reason_text());
    return;
  }
  if (cancel.reason() == msg::CANCEL_REASON_QUERY_REPLACED ||
      cancel.reason() == msg::CANCEL_REASON_QUERY_ABORTED) {
    // Another client took the planner over: waiting for waypoints would only time out.
    hold(true);
    status_.queries_failed(status_.queries_failed() + 1);
    setState(msg::MISSION_STATE_FAILED,
             "the planner dropped this mission's query: " + cancel.reason_text());
    return;
  }
  if (cancel.reason() == msg::CANCEL_REASON_UNKNOWN_QUERY) {
    reissueLostQuery(cancel, now);
    return;
  }
  if (cancel.reason() == msg::CANCEL_REASON_PLANNER_ERROR) {
    hold(true);
    status_.queries_failed(status_.queries_failed() + 1);
    setState(msg::MISSION_STATE_FAILED, "planner refused the query: " + cancel.reason_text());
    return;
  }
  // The way is blocked: stop where we are and wait for the planner's replan.
  current_.reset();
  next_.reset();
  command_id_ = 0;
  next_requested_ = false;
  hold(true);
  waiting_since_ = now;
  setState(msg::MISSION_STATE_WAITING_FOR_WAYPOINT, "waypoint " + std::to_string(id) +
                                                        " cancelled (" + cancel.reason_text() +
                                                        "); waiting for the replan");
  requestWaypoint(0, now);
}

bool MissionExecutive::abort(const std::string& reason, double now) {
  (void)now;
  if (!running()) return false;
  abortToHold(reason);
  return true;
}

void MissionExecutive::hold(bool keep_position) {
  msg::ControllerCommand command;
  command.header().frame_id("world");
  command.command_id(next_command_id_++);
  if (keep_position) {
    command.mode(msg::CONTROL_MODE_HOLD);  // the controller holds where navigation says we are
  } else {
    // Stop and keep depth: a speed-0 setpoint on the current heading and depth needs no
    // horizontal position, so it stays safe when navigation has gone stale.
    command.mode(msg::CONTROL_MODE_SETPOINT);
    command.heading(yaw_);
    command.depth(position_ ? position_->z() : 0.0);
    command.surge_speed(0.0);
  }
  outbox_.commands.push_back(command);
}

void MissionExecutive::abortToHold(const std::string& reason) {
  // Before readiness the mission has not commanded the vehicle, and may have no navigation to
  // take a depth from (a setpoint at depth 0 would surface it): leave the controller alone.
  const bool commanded = status_.state() != msg::MISSION_STATE_CHECKING_READINESS;
  if (commanded) hold(false);
  current_.reset();
  next_.reset();
  command_id_ = 0;
  setState(msg::MISSION_STATE_ABORTED,
           reason + (commanded ? "; holding depth" : "; the vehicle was not commanded yet"));
}

}  // namespace auv::mission
