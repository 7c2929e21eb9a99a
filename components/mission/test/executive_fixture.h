#pragma once
// The mission executive with a clock of the test's own, shared by mission_executive_test.cc and
// mission_recovery_test.cc.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "auv/interfaces/msg_eigen.h"
#include "auv/mission/mission_executive.h"

namespace auv::mission::executive_test {

#define EXPECT_CONTAINS(text, part) \
  EXPECT_NE(std::string(text).find(part), std::string::npos) << "'" << (text) << "'"

inline const Eigen::Vector3d kStart(0.0, 0.0, 5.0);

inline MissionQuery query(const Eigen::Vector3d& goal, const std::string& name = "q") {
  MissionQuery q;
  q.name = name;
  q.goal = goal;
  q.goal_tolerance = 1.0;
  q.time_budget = 2.5;
  q.visibility_objective = false;
  q.expected_distance = 3.0;
  q.admissible_range = 1.5;
  q.bounds_min = {-50, -50, 0};
  q.bounds_max = {50, 50, 20};
  return q;
}

inline msg::Point point(const Eigen::Vector3d& v) { return interfaces::toPoint(v); }
inline Eigen::Vector3d vector(const msg::Point& p) { return interfaces::toEigen(p); }

class MissionExecutiveTest : public ::testing::Test {
 protected:
  static ExecutiveOptions defaults() {
    ExecutiveOptions o;
    o.odometry_timeout = 1.0;
    o.controller_timeout = 5.0;
    o.readiness_timeout = 60.0;
    o.no_solution_timeout = 30.0;
    o.request_distance = 1.5;
    o.request_period = 2.0;
    return o;
  }

  MissionExecutive executive{defaults()};
  double t = 100.0;  // s, the fake clock
  Eigen::Vector3d vehicle = kStart;
  double yaw = 0.3;
  uint64_t next_waypoint_id = 1;

  msg::MissionState state() const { return executive.status().state(); }
  std::string message() const { return executive.status().message(); }

  void odometry() { executive.onOdometry(vehicle, yaw, t); }
  /// The vehicle moves to `position` (one odometry message).
  void moveTo(const Eigen::Vector3d& position) {
    vehicle = position;
    odometry();
  }
  void controller(bool safety = false, uint64_t active = 0, bool reached = false) {
    msg::ControllerStatus status;
    status.active_command_id(active);
    status.state(safety ? msg::CONTROLLER_STATE_SAFETY_MANEUVER : msg::CONTROLLER_STATE_IDLE);
    status.reached(reached);
    status.safety_maneuver(safety);
    if (safety) {
      status.safety_reason(safety_reason);
      status.safety_text("altitude 0.8 m < 1.5 m");
    }
    executive.onControllerStatus(status, t);
  }
  /// Time passes with fresh navigation and controller status (in a safety manoeuvre while
  /// `manoeuvre`), then a tick.
  void advance(double seconds) {
    t += seconds;
    odometry();
    controller(manoeuvre, active_command);
    executive.tick(t);
  }
  bool manoeuvre = false;       ///< the controller reports a safety manoeuvre (advance())
  uint64_t active_command = 0;  ///< the command the controller reports (advance(); follow())
  msg::SafetyReason safety_reason = msg::SAFETY_REASON_MIN_ALTITUDE;  ///< of controller(true)

  /// Starts `queries` with everything ready; returns the outbox of the start.
  MissionExecutive::Outbox startReady(const std::vector<MissionQuery>& queries) {
    odometry();
    controller();
    executive.setPlannerPresent(true);
    std::string why;
    EXPECT_TRUE(executive.start("m-1", queries, t, &why)) << why;
    return executive.takeOutbox();
  }

  msg::Waypoint waypoint(const Eigen::Vector3d& position, bool is_final = false) {
    msg::Waypoint w;
    w.waypoint_id(next_waypoint_id++);
    w.query_id(executive.status().current_query_id());
    w.position(point(position));
    w.heading(0.7);
    w.speed(0.5);
    w.tolerance(0.5);
    w.is_final(is_final);
    return w;
  }
  /// Sends a waypoint; returns the controller command it produced.
  msg::ControllerCommand follow(const msg::Waypoint& w) {
    executive.onWaypoint(w, t);
    auto out = executive.takeOutbox();
    EXPECT_EQ(out.commands.size(), 1u);
    if (!out.commands.empty()) active_command = out.commands.back().command_id();
    return out.commands.empty() ? msg::ControllerCommand() : out.commands.back();
  }

  msg::WaypointCancel cancel(uint64_t waypoint_id, msg::CancelReason reason,
                             uint64_t query_id = 0) {
    msg::WaypointCancel c;
    c.waypoint_id(waypoint_id);
    c.query_id(query_id != 0 ? query_id : executive.status().current_query_id());
    c.reason(reason);
    c.reason_text("root at (3, 0, 5) is occupied");
    return c;
  }

  /// The stop-and-keep-depth command of an abort.
  void expectDepthHold(const MissionExecutive::Outbox& out, double depth) {
    ASSERT_EQ(out.commands.size(), 1u);
    const msg::ControllerCommand& hold = out.commands.front();
    EXPECT_EQ(hold.mode(), msg::CONTROL_MODE_SETPOINT);
    EXPECT_EQ(hold.surge_speed(), 0.0);
    EXPECT_EQ(hold.depth(), depth);
    EXPECT_EQ(hold.heading(), yaw);
    EXPECT_NE(hold.command_id(), 0u);
  }
};

}  // namespace auv::mission::executive_test
