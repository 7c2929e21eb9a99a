// The mission handler's state machine (docs/paper.md §2.3) driven with a clock of the test's own:
// readiness, queries and waypoint requests, waypoints to the controller, arrival and prefetch,
// cancels and replans, and every way a mission ends (succeeded, aborted to a hold, failed).
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "auv/interfaces/msg_eigen.h"
#include "auv/mission/mission_executive.h"
#include "executive_fixture.h"

namespace auv::mission {
namespace {
using namespace executive_test;

// ---- readiness --------------------------------------------------------------------------

TEST_F(MissionExecutiveTest, StaysCheckingReadinessWithTheReason) {
  std::string why;
  ASSERT_TRUE(executive.start("m-1", {query({10, 0, 5})}, t, &why)) << why;
  EXPECT_TRUE(executive.running());
  EXPECT_EQ(executive.status().mission_id(), "m-1");
  EXPECT_EQ(executive.status().query_count(), 1u);
  EXPECT_EQ(state(), msg::MISSION_STATE_CHECKING_READINESS);
  EXPECT_CONTAINS(message(), "not ready: no navigation");

  odometry();  // navigation, then it goes stale
  t += 1.5;
  executive.tick(t);
  EXPECT_CONTAINS(message(), "navigation stale");

  odometry();
  executive.tick(t);
  EXPECT_CONTAINS(message(), "no controller status");

  controller(/*safety=*/true);
  executive.tick(t);
  EXPECT_CONTAINS(message(), "safety manoeuvre: altitude 0.8 m < 1.5 m");
  EXPECT_EQ(state(), msg::MISSION_STATE_CHECKING_READINESS);  // not aborted before it began

  controller();
  executive.tick(t);
  EXPECT_CONTAINS(message(), "no planner");

  // The controller status also goes stale.
  executive.setPlannerPresent(true);
  t += 6.0;
  odometry();
  executive.tick(t);
  EXPECT_CONTAINS(message(), "no controller status");

  auto out = executive.takeOutbox();
  EXPECT_TRUE(out.status_changed);
  EXPECT_TRUE(out.queries.empty());
  EXPECT_TRUE(out.requests.empty());
  EXPECT_TRUE(out.commands.empty());
  EXPECT_EQ(state(), msg::MISSION_STATE_CHECKING_READINESS);

  controller();
  executive.tick(t);
  EXPECT_EQ(state(), msg::MISSION_STATE_WAITING_FOR_WAYPOINT);
  EXPECT_EQ(executive.takeOutbox().queries.size(), 1u);
}

TEST_F(MissionExecutiveTest, NotReadyWithinReadinessTimeoutFails) {
  std::string why;
  ASSERT_TRUE(executive.start("m-1", {query({10, 0, 5})}, t, &why));
  odometry();
  executive.tick(t + 59.0);
  EXPECT_EQ(state(), msg::MISSION_STATE_CHECKING_READINESS);
  executive.tick(t + 60.5);
  EXPECT_EQ(state(), msg::MISSION_STATE_FAILED);
  EXPECT_CONTAINS(message(), "not ready after 60.00 s");
  EXPECT_CONTAINS(message(), "navigation stale");
  EXPECT_FALSE(executive.running());
  EXPECT_TRUE(executive.takeOutbox().commands.empty());  // never commanded the vehicle
}

TEST_F(MissionExecutiveTest, ReadyMissionSendsTheQueryFromTheVehicleAndAsksForAWaypoint) {
  MissionQuery q = query({10, -4, 6});
  const auto out = startReady({q});
  EXPECT_EQ(state(), msg::MISSION_STATE_WAITING_FOR_WAYPOINT);
  ASSERT_EQ(out.queries.size(), 1u);
  const msg::PlannerQuery& sent = out.queries.front();
  EXPECT_NE(sent.query_id(), 0u);
  EXPECT_EQ(vector(sent.start().position()), kStart);
  EXPECT_NEAR(2.0 * std::atan2(sent.start().orientation().z(), sent.start().orientation().w()), yaw,
              1e-12);
  EXPECT_EQ(vector(sent.goal().position()), q.goal);
  EXPECT_EQ(sent.goal_tolerance(), q.goal_tolerance);
  EXPECT_EQ(sent.time_budget(), q.time_budget);
  EXPECT_EQ(sent.objective(), msg::PLANNER_OBJECTIVE_PATH_LENGTH);
  EXPECT_EQ(sent.expected_distance(), q.expected_distance);
  EXPECT_EQ(sent.admissible_range(), q.admissible_range);
  EXPECT_EQ(vector(sent.bounds_max()), q.bounds_max);
  EXPECT_FALSE(sent.fixed_depth());
  ASSERT_EQ(out.requests.size(), 1u);
  EXPECT_EQ(out.requests.front().query_id(), sent.query_id());
  EXPECT_EQ(out.requests.front().reached_waypoint_id(), 0u);
  EXPECT_TRUE(out.commands.empty());
  EXPECT_EQ(executive.status().current_query_id(), sent.query_id());
  EXPECT_EQ(executive.status().current_query_index(), 0);
}

TEST_F(MissionExecutiveTest, FixedDepthQueryWithoutDepthPlansAtTheVehiclesDepth) {
  MissionQuery q = query({10, 0, 0});
  q.fixed_depth = true;
  vehicle = {1, 2, 7.5};
  const auto out = startReady({q});
  ASSERT_EQ(out.queries.size(), 1u);
  EXPECT_TRUE(out.queries.front().fixed_depth());
  EXPECT_EQ(out.queries.front().depth(), 7.5);
}

TEST_F(MissionExecutiveTest, LaterFixedDepthQueriesKeepTheFirstQuerysPlane) {
  MissionQuery first = query({10, 0, 0}, "first");
  first.fixed_depth = true;
  MissionQuery second = query({20, 0, 0}, "second");
  second.fixed_depth = true;
  vehicle = {0, 0, 3.0};
  const auto out = startReady({first, second});
  ASSERT_EQ(out.queries.size(), 1u);
  EXPECT_EQ(out.queries.front().depth(), 3.0);
  follow(waypoint({10, 0, 3.0}, true));
  moveTo({10, 0, 2.6});  // arrives having risen 0.4 m (positive buoyancy)
  const auto next = executive.takeOutbox();
  ASSERT_EQ(next.queries.size(), 1u);
  EXPECT_EQ(next.queries.front().depth(), 3.0);  // the mission's plane, not 2.6
}

// ---- waypoints ----------------------------------------------------------------------------

TEST_F(MissionExecutiveTest, WaypointBecomesAControllerWaypointCommand) {
  startReady({query({10, 0, 5})});
  const msg::Waypoint w = waypoint({4, 0, 5});
  const msg::ControllerCommand command = follow(w);
  EXPECT_EQ(command.mode(), msg::CONTROL_MODE_WAYPOINT);
  EXPECT_NE(command.command_id(), 0u);
  EXPECT_EQ(vector(command.position()), Eigen::Vector3d(4, 0, 5));
  EXPECT_EQ(command.depth(), 5.0);
  EXPECT_EQ(command.heading(), 0.7);
  EXPECT_EQ(command.surge_speed(), 0.5);
  EXPECT_EQ(command.tolerance(), 0.5);
  // factor 4 x 4 m / 0.5 m/s + 30 s margin.
  EXPECT_DOUBLE_EQ(command.timeout(), 4.0 * 4.0 / 0.5 + 30.0);
  EXPECT_EQ(state(), msg::MISSION_STATE_EXECUTING);
  EXPECT_EQ(executive.status().current_waypoint_id(), w.waypoint_id());
  EXPECT_EQ(executive.status().waypoints_received(), 1u);

  // A repeat of the same waypoint, or one of another query, changes nothing.
  executive.onWaypoint(w, t);
  msg::Waypoint other = waypoint({1, 1, 5});
  other.query_id(other.query_id() + 7);
  executive.onWaypoint(other, t);
  const auto out = executive.takeOutbox();
  EXPECT_TRUE(out.commands.empty());
  EXPECT_EQ(executive.status().waypoints_received(), 1u);
}

TEST_F(MissionExecutiveTest, NextWaypointIsRequestedWithinRequestDistance) {
  startReady({query({10, 0, 5})});
  const msg::Waypoint w = waypoint({4, 0, 5});
  follow(w);
  moveTo({1, 0, 5});  // 3 m away
  EXPECT_TRUE(executive.takeOutbox().requests.empty());
  moveTo({2.7, 0, 5});  // 1.3 m: within request_distance 1.5, outside tolerance 0.5
  auto out = executive.takeOutbox();
  ASSERT_EQ(out.requests.size(), 1u);
  EXPECT_EQ(out.requests.front().reached_waypoint_id(), w.waypoint_id());
  EXPECT_EQ(out.requests.front().query_id(), w.query_id());
  EXPECT_TRUE(out.commands.empty());
  EXPECT_EQ(state(), msg::MISSION_STATE_EXECUTING);
  moveTo({3.0, 0, 5});  // asked once, not on every odometry message
  EXPECT_TRUE(executive.takeOutbox().requests.empty());
}

TEST_F(MissionExecutiveTest, ControllerArrivalCommandsThePrefetchedWaypoint) {
  startReady({query({10, 0, 5})});
  const msg::ControllerCommand first = follow(waypoint({4, 0, 5}));
  const msg::Waypoint second = waypoint({8, 1, 5});
  executive.onWaypoint(second, t);  // prefetched: not commanded yet
  EXPECT_TRUE(executive.takeOutbox().commands.empty());
  EXPECT_EQ(executive.status().waypoints_received(), 2u);

  controller(false, first.command_id() + 100, /*reached=*/true);  // someone else's command
  EXPECT_TRUE(executive.takeOutbox().commands.empty());
  controller(false, first.command_id(), /*reached=*/false);
  EXPECT_TRUE(executive.takeOutbox().commands.empty());

  controller(false, first.command_id(), /*reached=*/true);
  const auto out = executive.takeOutbox();
  ASSERT_EQ(out.commands.size(), 1u);
  EXPECT_EQ(out.commands.front().mode(), msg::CONTROL_MODE_WAYPOINT);
  EXPECT_EQ(vector(out.commands.front().position()), Eigen::Vector3d(8, 1, 5));
  EXPECT_NE(out.commands.front().command_id(), first.command_id());
  EXPECT_EQ(executive.status().waypoints_reached(), 1u);
  EXPECT_EQ(executive.status().current_waypoint_id(), second.waypoint_id());
  EXPECT_EQ(state(), msg::MISSION_STATE_EXECUTING);

  // The old command's "reached" repeated does not skip the new waypoint.
  controller(false, first.command_id(), /*reached=*/true);
  EXPECT_TRUE(executive.takeOutbox().commands.empty());
  EXPECT_EQ(executive.status().waypoints_reached(), 1u);
}

TEST_F(MissionExecutiveTest, OdometryArrivalWithoutANextWaypointRequestsIt) {
  startReady({query({10, 0, 5})});
  const msg::Waypoint w = waypoint({4, 0, 5});
  follow(w);
  moveTo({3.0, 0, 5});  // the early request
  auto out = executive.takeOutbox();
  ASSERT_EQ(out.requests.size(), 1u);
  EXPECT_EQ(out.requests.front().reached_waypoint_id(), w.waypoint_id());
  moveTo({3.8, 0.1, 5});  // within tolerance 0.5, and no waypoint prefetched yet
  out = executive.takeOutbox();
  EXPECT_EQ(state(), msg::MISSION_STATE_WAITING_FOR_WAYPOINT);
  EXPECT_CONTAINS(message(), "reached; waiting for the next");
  EXPECT_EQ(executive.status().waypoints_reached(), 1u);
  EXPECT_TRUE(out.requests.empty());  // the early request is in flight: not asked twice
  EXPECT_TRUE(out.commands.empty());  // the controller keeps the reached waypoint

  const msg::ControllerCommand next = follow(waypoint({8, 0, 5}));
  EXPECT_EQ(vector(next.position()), Eigen::Vector3d(8, 0, 5));
  EXPECT_EQ(state(), msg::MISSION_STATE_EXECUTING);
}

TEST_F(MissionExecutiveTest, ArrivalWithoutEarlyRequestAsksOnArrival) {
  ExecutiveOptions options = defaults();
  options.request_distance = 0.0;  // on arrival only
  MissionExecutive on_arrival(options);
  on_arrival.onOdometry(kStart, 0.0, t);
  msg::ControllerStatus status;
  on_arrival.onControllerStatus(status, t);
  on_arrival.setPlannerPresent(true);
  std::string why;
  ASSERT_TRUE(on_arrival.start("m", {query({10, 0, 5})}, t, &why));
  const uint64_t query_id = on_arrival.status().current_query_id();
  on_arrival.takeOutbox();
  msg::Waypoint w;
  w.waypoint_id(3);
  w.query_id(query_id);
  w.position(point({4, 0, 5}));
  w.speed(0.5);
  w.tolerance(0.5);
  on_arrival.onWaypoint(w, t);
  on_arrival.onOdometry({3.2, 0, 5}, 0.0, t);  // 0.8 m: no early request
  EXPECT_TRUE(on_arrival.takeOutbox().requests.empty());
  on_arrival.onOdometry({3.9, 0, 5}, 0.0, t);
  const auto out = on_arrival.takeOutbox();
  ASSERT_EQ(out.requests.size(), 1u);
  EXPECT_EQ(out.requests.front().reached_waypoint_id(), 3u);
  EXPECT_EQ(on_arrival.status().state(), msg::MISSION_STATE_WAITING_FOR_WAYPOINT);
}

TEST_F(MissionExecutiveTest, QueriesRunInOrderToSuccess) {
  const Eigen::Vector3d goal1(10, 0, 5), goal2(10, 10, 8);
  const auto start = startReady({query(goal1, "first"), query(goal2, "second")});
  const uint64_t first_query = start.queries.front().query_id();

  follow(waypoint({5, 0, 5}));
  moveTo({5, 0, 5});  // reached, nothing prefetched: waits
  EXPECT_EQ(state(), msg::MISSION_STATE_WAITING_FOR_WAYPOINT);
  executive.takeOutbox();
  follow(waypoint(goal1, /*is_final=*/true));
  moveTo({9.8, 0, 5});  // the final waypoint reached: the next query starts from here
  auto out = executive.takeOutbox();
  EXPECT_EQ(executive.status().queries_succeeded(), 1u);
  EXPECT_EQ(executive.status().current_query_index(), 1);
  EXPECT_EQ(state(), msg::MISSION_STATE_WAITING_FOR_WAYPOINT);
  ASSERT_EQ(out.queries.size(), 1u);
  const msg::PlannerQuery& second = out.queries.front();
  EXPECT_NE(second.query_id(), first_query);
  EXPECT_EQ(vector(second.start().position()), Eigen::Vector3d(9.8, 0, 5));
  EXPECT_EQ(vector(second.goal().position()), goal2);
  ASSERT_EQ(out.requests.size(), 1u);
  EXPECT_EQ(out.requests.front().query_id(), second.query_id());
  EXPECT_EQ(out.requests.front().reached_waypoint_id(), 0u);
  EXPECT_TRUE(out.commands.empty());
  EXPECT_EQ(executive.status().current_query_id(), second.query_id());

  const msg::ControllerCommand last = follow(waypoint(goal2, /*is_final=*/true));
  controller(false, last.command_id(), /*reached=*/true);
  out = executive.takeOutbox();
  EXPECT_EQ(state(), msg::MISSION_STATE_SUCCEEDED);
  EXPECT_FALSE(executive.running());
  EXPECT_EQ(executive.status().queries_succeeded(), 2u);
  EXPECT_EQ(executive.status().queries_failed(), 0u);
  EXPECT_EQ(executive.status().waypoints_received(), 3u);
  EXPECT_EQ(executive.status().waypoints_reached(), 3u);
  EXPECT_EQ(executive.status().current_query_index(), -1);
  EXPECT_CONTAINS(message(), "all 2 queries");
  ASSERT_EQ(out.commands.size(), 1u);
  EXPECT_EQ(out.commands.front().mode(), msg::CONTROL_MODE_HOLD);
  EXPECT_TRUE(out.queries.empty());

  // Ended missions ignore late traffic; a new one may start.
  executive.onWaypoint(waypoint(goal2), t);
  moveTo(goal2);
  EXPECT_TRUE(executive.takeOutbox().commands.empty());
  std::string why;
  EXPECT_TRUE(executive.start("m-2", {query(goal1)}, t, &why)) << why;
  EXPECT_EQ(executive.status().queries_succeeded(), 0u);
}

TEST_F(MissionExecutiveTest, ReachingTheGoalEndsTheQueryBeforeTheFinalWaypoint) {
  startReady({query({10, 0, 5})});
  follow(waypoint({9.5, 0, 5}));  // not final, but within goal_tolerance 1 of the goal
  moveTo({9.5, 0, 5});
  EXPECT_EQ(state(), msg::MISSION_STATE_SUCCEEDED);
}

// ---- cancels and replans ------------------------------------------------------------------

TEST_F(MissionExecutiveTest, CancelOfTheActiveWaypointHoldsAndAsksForTheReplan) {
  startReady({query({10, 0, 5})});
  const msg::Waypoint w = waypoint({4, 0, 5});
  follow(w);
  executive.onCancel(cancel(w.waypoint_id(), msg::CANCEL_REASON_ROOT_IN_COLLISION), t);
  const auto out = executive.takeOutbox();
  EXPECT_EQ(state(), msg::MISSION_STATE_WAITING_FOR_WAYPOINT);
  EXPECT_CONTAINS(message(), "cancelled (root at (3, 0, 5) is occupied)");
  EXPECT_EQ(executive.status().waypoints_cancelled(), 1u);
  ASSERT_EQ(out.commands.size(), 1u);
  EXPECT_EQ(out.commands.front().mode(), msg::CONTROL_MODE_HOLD);
  ASSERT_EQ(out.requests.size(), 1u);
  EXPECT_EQ(out.requests.front().query_id(), w.query_id());
  EXPECT_EQ(out.requests.front().reached_waypoint_id(), 0u);

  // The replan's waypoint is followed.
  const msg::ControllerCommand replanned = follow(waypoint({2, 3, 5}));
  EXPECT_EQ(replanned.mode(), msg::CONTROL_MODE_WAYPOINT);
  EXPECT_EQ(vector(replanned.position()), Eigen::Vector3d(2, 3, 5));
  EXPECT_EQ(state(), msg::MISSION_STATE_EXECUTING);
}

TEST_F(MissionExecutiveTest, CancelOfAnotherQueryOrWaypointIsIgnored) {
  startReady({query({10, 0, 5})});
  const msg::Waypoint w = waypoint({4, 0, 5});
  follow(w);
  executive.onCancel(
      cancel(w.waypoint_id(), msg::CANCEL_REASON_ROOT_IN_COLLISION, w.query_id() + 1), t);
  executive.onCancel(cancel(w.waypoint_id() + 5, msg::CANCEL_REASON_NO_SOLUTION), t);
  const auto out = executive.takeOutbox();
  EXPECT_TRUE(out.commands.empty());
  EXPECT_TRUE(out.requests.empty());
  EXPECT_EQ(state(), msg::MISSION_STATE_EXECUTING);
  EXPECT_EQ(executive.status().waypoints_cancelled(), 0u);
}

TEST_F(MissionExecutiveTest, NoSolutionAbortsToADepthHold) {
  startReady({query({10, 0, 5})});
  const msg::Waypoint w = waypoint({4, 0, 5});
  follow(w);
  moveTo({1.5, 0.5, 6.25});
  executive.takeOutbox();
  executive.onCancel(cancel(0, msg::CANCEL_REASON_NO_SOLUTION), t);  // 0: any of the query
  const auto out = executive.takeOutbox();
  EXPECT_EQ(state(), msg::MISSION_STATE_ABORTED);
  EXPECT_CONTAINS(message(), "planner found no solution");
  expectDepthHold(out, 6.25);
  EXPECT_FALSE(executive.running());
}

TEST_F(MissionExecutiveTest, PlannerErrorFailsTheMission) {
  startReady({query({10, 0, 5})});
  executive.onCancel(cancel(0, msg::CANCEL_REASON_PLANNER_ERROR), t);
  const auto out = executive.takeOutbox();
  EXPECT_EQ(state(), msg::MISSION_STATE_FAILED);
  EXPECT_EQ(executive.status().queries_failed(), 1u);
  ASSERT_EQ(out.commands.size(), 1u);
  EXPECT_EQ(out.commands.front().mode(), msg::CONTROL_MODE_HOLD);
}

// A restarted planner answers with UNKNOWN_QUERY: the query is given again from where the
// vehicle is (new id), and the mission goes on.
TEST_F(MissionExecutiveTest, QueryUnknownToARestartedPlannerIsReissuedFromHere) {
  startReady({query({10, 0, 5})});
  const msg::Waypoint w = waypoint({4, 0, 5});
  follow(w);
  moveTo({2.0, 0.5, 5.0});
  executive.takeOutbox();
  executive.onCancel(cancel(0, msg::CANCEL_REASON_UNKNOWN_QUERY), t);
  const auto out = executive.takeOutbox();
  EXPECT_EQ(state(), msg::MISSION_STATE_WAITING_FOR_WAYPOINT);
  EXPECT_TRUE(executive.running());
  ASSERT_EQ(out.commands.size(), 1u);
  EXPECT_EQ(out.commands.front().mode(), msg::CONTROL_MODE_HOLD);
  ASSERT_EQ(out.queries.size(), 1u);
  EXPECT_GT(out.queries.front().query_id(), w.query_id());
  EXPECT_EQ(vector(out.queries.front().start().position()), Eigen::Vector3d(2.0, 0.5, 5.0));
  ASSERT_EQ(out.requests.size(), 1u);
  EXPECT_EQ(out.requests.front().query_id(), out.queries.front().query_id());
  ASSERT_EQ(out.events.size(), 1u);
  EXPECT_EQ(out.events.front().name, "PLANNER_REISSUE");
  EXPECT_EQ(executive.status().recoveries(), 0u) << "a planner restart is not a recovery";

  // The new planner's waypoints (ids from 1 again) are followed.
  msg::Waypoint again = waypoint({6, 0, 5});
  again.query_id(out.queries.front().query_id());
  again.waypoint_id(1);
  const msg::ControllerCommand followed = follow(again);
  EXPECT_EQ(followed.mode(), msg::CONTROL_MODE_WAYPOINT);
  EXPECT_EQ(state(), msg::MISSION_STATE_EXECUTING);
}

// A planner that restarts again and again before its first waypoint does not keep the mission
// waiting forever: the no-solution clock runs on across the re-issues.
TEST_F(MissionExecutiveTest, PlannerLoosingTheQueryBeforeAnyWaypointStillTimesOut) {
  startReady({query({10, 0, 5})});
  for (int i = 0; i < 25; ++i) advance(1.0);
  executive.onCancel(cancel(0, msg::CANCEL_REASON_UNKNOWN_QUERY), t);
  EXPECT_EQ(state(), msg::MISSION_STATE_WAITING_FOR_WAYPOINT);
  for (int i = 0; i < 6 && executive.running(); ++i) advance(1.0);
  EXPECT_EQ(state(), msg::MISSION_STATE_ABORTED);
  EXPECT_CONTAINS(message(), "no_solution_timeout");
}

TEST_F(MissionExecutiveTest, QueryReplacedByAnotherClientFailsTheMission) {
  startReady({query({10, 0, 5})});
  follow(waypoint({4, 0, 5}));
  executive.onCancel(cancel(0, msg::CANCEL_REASON_QUERY_REPLACED), t);
  const auto out = executive.takeOutbox();
  EXPECT_EQ(state(), msg::MISSION_STATE_FAILED);
  EXPECT_CONTAINS(message(), "dropped this mission's query");
  ASSERT_EQ(out.commands.size(), 1u);
  EXPECT_EQ(out.commands.front().mode(), msg::CONTROL_MODE_HOLD);
  EXPECT_TRUE(out.requests.empty());  // no waiting for waypoints that cannot come
}

// ---- aborts -------------------------------------------------------------------------------

// A navigation dropout holds depth (safe without a position) and is recovered once navigation
// returns: the query again from where the vehicle is.
TEST_F(MissionExecutiveTest, StaleNavigationWhileExecutingHoldsDepthAndRecovers) {
  startReady({query({10, 0, 5})});
  follow(waypoint({4, 0, 5}));
  moveTo({2, 0, 5.5});  // the last navigation
  executive.takeOutbox();
  // The controller still reports; navigation does not.
  t += 0.9;
  controller(false, active_command);
  executive.tick(t);
  EXPECT_EQ(state(), msg::MISSION_STATE_EXECUTING);
  EXPECT_TRUE(executive.takeOutbox().commands.empty());
  t += 0.2;
  controller(false, active_command);
  executive.tick(t);
  auto out = executive.takeOutbox();
  EXPECT_EQ(state(), msg::MISSION_STATE_RECOVERING);
  EXPECT_CONTAINS(message(), "navigation stale");
  EXPECT_CONTAINS(message(), "holding depth");
  expectDepthHold(out, 5.5);
  ASSERT_EQ(out.events.size(), 1u);
  EXPECT_EQ(out.events[0].name, "RECOVERY_START");

  // Still no navigation: nothing is re-issued.
  for (int i = 0; i < 10; ++i) {
    t += 1.0;
    controller(false, active_command);
    executive.tick(t);
  }
  EXPECT_EQ(state(), msg::MISSION_STATE_RECOVERING);
  EXPECT_TRUE(executive.takeOutbox().queries.empty());
  // Navigation back: HOLD, then the query from here.
  advance(1.0);
  out = executive.takeOutbox();
  ASSERT_EQ(out.commands.size(), 1u);
  EXPECT_EQ(out.commands[0].mode(), msg::CONTROL_MODE_HOLD);
  advance(5.5);
  out = executive.takeOutbox();
  ASSERT_EQ(out.queries.size(), 1u);
  EXPECT_EQ(vector(out.queries[0].start().position()), Eigen::Vector3d(2, 0, 5.5));
  EXPECT_EQ(state(), msg::MISSION_STATE_WAITING_FOR_WAYPOINT);
}

// A silent controller may be a restarting one: the mission waits for it as for a manoeuvre,
// then holds and re-issues the query from where the vehicle is.
TEST_F(MissionExecutiveTest, SilentControllerIsWaitedForThenTheQueryIsReissued) {
  startReady({query({10, 0, 5})});
  follow(waypoint({4, 0, 5}));
  executive.takeOutbox();
  // Navigation keeps coming; the controller's status stops.
  for (int i = 0; i < 4; ++i) {
    t += 1.0;
    odometry();
    executive.tick(t);
  }
  EXPECT_EQ(state(), msg::MISSION_STATE_EXECUTING);
  t += 1.5;  // 5.5 s > controller_timeout 5 s
  odometry();
  executive.tick(t);
  EXPECT_EQ(state(), msg::MISSION_STATE_RECOVERING);
  EXPECT_CONTAINS(message(), "controller silent");
  auto out = executive.takeOutbox();
  EXPECT_TRUE(out.commands.empty()) << "nobody to command";
  ASSERT_EQ(out.events.size(), 1u);
  EXPECT_EQ(out.events[0].name, "RECOVERY_START");
  // Back: a hold, then the query again after recovery_hold.
  advance(1.0);
  out = executive.takeOutbox();
  ASSERT_EQ(out.commands.size(), 1u);
  EXPECT_EQ(out.commands[0].mode(), msg::CONTROL_MODE_HOLD);
  advance(5.5);
  EXPECT_EQ(executive.takeOutbox().queries.size(), 1u);
  EXPECT_EQ(state(), msg::MISSION_STATE_WAITING_FOR_WAYPOINT);
}

// A controller restarted within controller_timeout reports again, but without the command
// it had: the mission notices and recovers instead of waiting for an arrival that cannot come.
TEST_F(MissionExecutiveTest, ControllerThatLostItsCommandIsRecovered) {
  startReady({query({10, 0, 5})});
  follow(waypoint({4, 0, 5}));
  advance(1.0);
  active_command = 0;  // restarted: no command
  for (int i = 0; i < 3; ++i) advance(1.0);
  EXPECT_EQ(state(), msg::MISSION_STATE_EXECUTING) << "a command on its way is not lost";
  for (int i = 0; i < 4; ++i) advance(1.0);  // no command for 6 s > controller_timeout
  EXPECT_EQ(state(), msg::MISSION_STATE_RECOVERING);
  EXPECT_CONTAINS(message(), "the controller has lost command");
}

TEST_F(MissionExecutiveTest, ControllerSilentPastRecoveryTimeoutAborts) {
  startReady({query({10, 0, 5})});
  follow(waypoint({4, 0, 5}));
  for (int i = 0; i < 300 && executive.running(); ++i) {
    t += 1.0;
    odometry();
    executive.tick(t);
  }
  EXPECT_EQ(state(), msg::MISSION_STATE_ABORTED);
  EXPECT_CONTAINS(message(), "recovery given up: a silent controller");
  EXPECT_CONTAINS(message(), "recovery_timeout");
}

TEST_F(MissionExecutiveTest, StaleNavigationWhileWaitingHoldsDepthToo) {
  startReady({query({10, 0, 5})});
  t += 1.5;
  controller();
  executive.tick(t);
  EXPECT_EQ(state(), msg::MISSION_STATE_RECOVERING);
  expectDepthHold(executive.takeOutbox(), kStart.z());
}

TEST_F(MissionExecutiveTest, NavigationThatNeverReturnsAbortsAfterRecoveryTimeout) {
  startReady({query({10, 0, 5})});
  for (int i = 0; i < 400 && executive.running(); ++i) {
    t += 1.0;
    controller();
    executive.tick(t);
  }
  EXPECT_EQ(state(), msg::MISSION_STATE_ABORTED);
  EXPECT_CONTAINS(message(), "recovery given up: stale navigation");
}

TEST_F(MissionExecutiveTest, UnansweredRequestIsRepeatedEveryRequestPeriod) {
  const auto start = startReady({query({10, 0, 5})});
  ASSERT_EQ(start.requests.size(), 1u);
  advance(1.0);
  EXPECT_TRUE(executive.takeOutbox().requests.empty());
  advance(1.0);  // 2 s after the first
  auto out = executive.takeOutbox();
  ASSERT_EQ(out.requests.size(), 1u);
  EXPECT_EQ(out.requests.front().reached_waypoint_id(), 0u);
  advance(1.0);
  EXPECT_TRUE(executive.takeOutbox().requests.empty());
  advance(1.0);
  EXPECT_EQ(executive.takeOutbox().requests.size(), 1u);

  // After an arrival, the repeat names the reached waypoint.
  const msg::Waypoint w = waypoint({1, 0, 5});
  follow(w);
  moveTo({1, 0, 5});
  executive.takeOutbox();
  advance(2.0);
  out = executive.takeOutbox();
  ASSERT_EQ(out.requests.size(), 1u);
  EXPECT_EQ(out.requests.front().reached_waypoint_id(), w.waypoint_id());
  EXPECT_EQ(state(), msg::MISSION_STATE_WAITING_FOR_WAYPOINT);
}

TEST_F(MissionExecutiveTest, NoWaypointWithinNoSolutionTimeoutAborts) {
  startReady({query({10, 0, 5})});
  for (int i = 0; i < 29; ++i) advance(1.0);
  EXPECT_EQ(state(), msg::MISSION_STATE_WAITING_FOR_WAYPOINT);
  advance(1.5);
  EXPECT_EQ(state(), msg::MISSION_STATE_ABORTED);
  EXPECT_CONTAINS(message(), "no waypoint from the planner");
  EXPECT_CONTAINS(message(), "no_solution_timeout");
  const auto out = executive.takeOutbox();
  ASSERT_FALSE(out.commands.empty());
  EXPECT_EQ(out.commands.back().mode(), msg::CONTROL_MODE_SETPOINT);
  EXPECT_EQ(out.commands.back().surge_speed(), 0.0);
}

TEST_F(MissionExecutiveTest, AbortHoldsDepthAndOnlyWhileRunning) {
  EXPECT_FALSE(executive.abort("operator", t));  // idle
  startReady({query({10, 0, 5})});
  follow(waypoint({4, 0, 5}));
  moveTo({1, 1, 4.5});
  executive.takeOutbox();
  ASSERT_TRUE(executive.abort("aborted by request", t));
  EXPECT_EQ(state(), msg::MISSION_STATE_ABORTED);
  EXPECT_CONTAINS(message(), "aborted by request");
  expectDepthHold(executive.takeOutbox(), 4.5);
  EXPECT_FALSE(executive.abort("again", t));
  EXPECT_TRUE(executive.takeOutbox().commands.empty());
}

TEST_F(MissionExecutiveTest, AbortBeforeReadinessCommandsNothing) {
  // No navigation yet: there is no depth to hold, and the mission never took control.
  std::string why;
  ASSERT_TRUE(executive.start("m-1", {query({10, 0, 5})}, t, &why));
  executive.takeOutbox();
  ASSERT_TRUE(executive.abort("operator", t));
  EXPECT_EQ(state(), msg::MISSION_STATE_ABORTED);
  EXPECT_TRUE(executive.takeOutbox().commands.empty());
}

TEST_F(MissionExecutiveTest, StartWhileRunningIsRefusedWithTheReason) {
  startReady({query({10, 0, 5})});
  std::string why;
  EXPECT_FALSE(executive.start("m-2", {query({1, 0, 5})}, t, &why));
  EXPECT_CONTAINS(why, "mission 'm-1' is WAITING_FOR_WAYPOINT");
  EXPECT_EQ(executive.status().mission_id(), "m-1");
  EXPECT_TRUE(executive.takeOutbox().queries.empty());

  MissionExecutive idle(defaults());
  EXPECT_FALSE(idle.start("empty", {}, t, &why));
  EXPECT_CONTAINS(why, "no queries");
}

TEST_F(MissionExecutiveTest, SafetyManoeuvreWhileExecutingRecovers) {
  startReady({query({10, 0, 5})});
  follow(waypoint({4, 0, 5}));
  controller(/*safety=*/true);
  const auto out = executive.takeOutbox();
  EXPECT_EQ(state(), msg::MISSION_STATE_RECOVERING);
  EXPECT_CONTAINS(message(), "MIN_ALTITUDE: altitude 0.8 m < 1.5 m");
  // The controller is in charge: the mission sends nothing over its manoeuvre, and later
  // waypoints of the interrupted query are not followed.
  EXPECT_TRUE(out.commands.empty());
  executive.onWaypoint(waypoint({8, 0, 5}), t);
  manoeuvre = true;
  advance(1.0);
  EXPECT_TRUE(executive.takeOutbox().commands.empty());
  EXPECT_EQ(state(), msg::MISSION_STATE_RECOVERING);
}

TEST(ExecutiveOptionsTest, InvalidOptionsNameTheField) {
  ExecutiveOptions options;
  options.request_period = 0.0;
  try {
    MissionExecutive executive(options);
    FAIL() << "accepted request_period 0";
  } catch (const std::invalid_argument& error) {
    EXPECT_CONTAINS(error.what(), "request_period");
  }
  options = ExecutiveOptions();
  options.request_distance = -1.0;
  EXPECT_THROW(MissionExecutive{options}, std::invalid_argument);
  for (double bad : {-1.0, 2.5, std::nan("")}) {
    options = ExecutiveOptions();
    options.max_recoveries = bad;
    try {
      MissionExecutive executive(options);
      FAIL() << "accepted max_recoveries " << bad;
    } catch (const std::invalid_argument& error) {
      EXPECT_CONTAINS(error.what(), "max_recoveries");
    }
  }
}

}  // namespace
}  // namespace auv::mission
