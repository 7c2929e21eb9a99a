// Missions that recover: a controller safety manoeuvre interrupts a query, the executive waits
// for it to end, holds, and re-issues the query from where the vehicle is; and every way a
// recovery gives up (exhausted, persisting, operator abort, manoeuvres that abort at once).
#include <gtest/gtest.h>

#include "executive_fixture.h"

namespace auv::mission {
namespace {
using namespace executive_test;

class MissionRecoveryTest : public MissionExecutiveTest {
 protected:
  static ExecutiveOptions recoveryOptions() {
    ExecutiveOptions o = defaults();
    o.max_recoveries = 2;
    o.recovery_hold = 5.0;
    o.recovery_timeout = 60.0;
    return o;
  }
  MissionRecoveryTest() { executive = MissionExecutive(recoveryOptions()); }

  /// A manoeuvre interrupts the query and is over after `seconds`: RECOVERING, then the HOLD.
  /// Returns the outbox of the moment the manoeuvre ended.
  MissionExecutive::Outbox interruptFor(double seconds) {
    controller(/*safety=*/true);
    EXPECT_EQ(state(), msg::MISSION_STATE_RECOVERING) << message();
    manoeuvre = true;
    for (double s = 0; s < seconds; s += 1.0) advance(1.0);
    executive.takeOutbox();
    manoeuvre = false;
    advance(1.0);
    return executive.takeOutbox();
  }
};

TEST_F(MissionRecoveryTest, MinAltitudeMidQueryHoldsThenReissuesTheQueryAndSucceeds) {
  const Eigen::Vector3d goal(10, 0, 5);
  startReady({query(goal)});
  const uint64_t first_query = executive.status().current_query_id();
  follow(waypoint({4, 0, 5}));
  moveTo({3, 0, 6});  // where the manoeuvre left the vehicle
  controller(/*safety=*/true);
  auto out = executive.takeOutbox();
  ASSERT_EQ(state(), msg::MISSION_STATE_RECOVERING);
  EXPECT_EQ(executive.status().recoveries(), 1u);
  ASSERT_EQ(out.events.size(), 1u);
  EXPECT_EQ(out.events[0].name, "RECOVERY_START");
  EXPECT_CONTAINS(out.events[0].detail, "recovery 1/2 of query 1 after MIN_ALTITUDE");
  EXPECT_TRUE(out.commands.empty());  // the controller refuses commands meanwhile

  // The manoeuvre lasts 20 s: the mission waits (no recovery_timeout yet).
  manoeuvre = true;
  for (int i = 0; i < 20; ++i) advance(1.0);
  out = executive.takeOutbox();
  EXPECT_TRUE(out.commands.empty());
  EXPECT_TRUE(out.queries.empty());
  EXPECT_EQ(state(), msg::MISSION_STATE_RECOVERING);

  // Over: HOLD where it is, for recovery_hold.
  manoeuvre = false;
  advance(1.0);
  out = executive.takeOutbox();
  ASSERT_EQ(out.commands.size(), 1u);
  EXPECT_EQ(out.commands[0].mode(), msg::CONTROL_MODE_HOLD);
  EXPECT_CONTAINS(message(), "holding 5.00 s");
  advance(4.0);
  out = executive.takeOutbox();
  EXPECT_TRUE(out.queries.empty());
  EXPECT_EQ(state(), msg::MISSION_STATE_RECOVERING);

  // Then the query again, from where the vehicle is, under a new id.
  advance(1.5);
  out = executive.takeOutbox();
  ASSERT_EQ(out.queries.size(), 1u);
  const msg::PlannerQuery& again = out.queries[0];
  EXPECT_NE(again.query_id(), first_query);
  EXPECT_EQ(vector(again.start().position()), Eigen::Vector3d(3, 0, 6));
  EXPECT_EQ(vector(again.goal().position()), goal);
  ASSERT_EQ(out.requests.size(), 1u);
  EXPECT_EQ(out.requests[0].query_id(), again.query_id());
  ASSERT_EQ(out.events.size(), 1u);
  EXPECT_EQ(out.events[0].name, "RECOVERY_REISSUE");
  EXPECT_CONTAINS(out.events[0].detail, "re-issued as query id");
  EXPECT_EQ(state(), msg::MISSION_STATE_WAITING_FOR_WAYPOINT);

  // A late waypoint of the interrupted query is not followed; the new query's are.
  msg::Waypoint stale = waypoint({8, 0, 5});
  stale.query_id(first_query);
  executive.onWaypoint(stale, t);
  EXPECT_TRUE(executive.takeOutbox().commands.empty());
  const msg::ControllerCommand command = follow(waypoint(goal, /*is_final=*/true));
  EXPECT_EQ(command.mode(), msg::CONTROL_MODE_WAYPOINT);
  moveTo(goal);
  EXPECT_EQ(state(), msg::MISSION_STATE_SUCCEEDED) << message();
  EXPECT_EQ(executive.status().recoveries(), 1u);
  EXPECT_EQ(executive.status().queries_succeeded(), 1u);
}

TEST_F(MissionRecoveryTest, RecoveriesExhaustedAbortNamingTheCount) {
  startReady({query({10, 0, 5})});
  for (int i = 0; i < 2; ++i) {
    follow(waypoint({4, 0, 5}));
    interruptFor(3.0);
    advance(6.0);  // hold, re-issue
    ASSERT_EQ(state(), msg::MISSION_STATE_WAITING_FOR_WAYPOINT) << message();
  }
  follow(waypoint({4, 0, 5}));
  controller(/*safety=*/true);
  EXPECT_EQ(state(), msg::MISSION_STATE_ABORTED);
  EXPECT_CONTAINS(message(), "recoveries exhausted (2 of max_recoveries 2");
  EXPECT_EQ(executive.status().recoveries(), 2u);
}

TEST_F(MissionRecoveryTest, RecoveriesAreCountedPerQuery) {
  startReady({query({10, 0, 5}, "a"), query({20, 0, 5}, "b")});
  for (int i = 0; i < 2; ++i) {
    follow(waypoint({4, 0, 5}));
    interruptFor(2.0);
    advance(6.0);
  }
  follow(waypoint({10, 0, 5}, /*is_final=*/true));
  moveTo({10, 0, 5});  // query a done: b has its own max_recoveries
  ASSERT_EQ(executive.status().current_query_index(), 1);
  follow(waypoint({14, 0, 5}));
  controller(/*safety=*/true);
  EXPECT_EQ(state(), msg::MISSION_STATE_RECOVERING) << message();
  EXPECT_EQ(executive.status().recoveries(), 3u);
}

TEST_F(MissionRecoveryTest, ManoeuvrePersistingPastRecoveryTimeoutAborts) {
  startReady({query({10, 0, 5})});
  follow(waypoint({4, 0, 5}));
  controller(/*safety=*/true);
  manoeuvre = true;
  for (int i = 0; i < 59; ++i) advance(1.0);
  EXPECT_EQ(state(), msg::MISSION_STATE_RECOVERING);
  advance(2.0);
  EXPECT_EQ(state(), msg::MISSION_STATE_ABORTED);
  EXPECT_CONTAINS(message(), "recovery given up");
  EXPECT_CONTAINS(message(), "recovery_timeout 60.00 s");
  EXPECT_CONTAINS(message(), "MIN_ALTITUDE");
}

TEST_F(MissionRecoveryTest, OperatorAbortWhileRecoveringAborts) {
  startReady({query({10, 0, 5})});
  follow(waypoint({4, 0, 5}));
  interruptFor(2.0);  // holding
  ASSERT_EQ(state(), msg::MISSION_STATE_RECOVERING);
  EXPECT_TRUE(executive.abort("operator abort", t));
  EXPECT_EQ(state(), msg::MISSION_STATE_ABORTED);
  EXPECT_CONTAINS(message(), "operator abort");
  expectDepthHold(executive.takeOutbox(), vehicle.z());
  advance(10.0);  // no re-issue after the abort
  EXPECT_TRUE(executive.takeOutbox().queries.empty());
}

TEST_F(MissionRecoveryTest, LeakLowBatteryAndOperatorManoeuvresAbortAtOnce) {
  for (msg::SafetyReason reason :
       {msg::SAFETY_REASON_LEAK, msg::SAFETY_REASON_LOW_BATTERY, msg::SAFETY_REASON_OPERATOR}) {
    executive = MissionExecutive(recoveryOptions());
    startReady({query({10, 0, 5})});
    follow(waypoint({4, 0, 5}));
    safety_reason = reason;
    controller(/*safety=*/true);
    EXPECT_EQ(state(), msg::MISSION_STATE_ABORTED) << static_cast<int>(reason);
    EXPECT_EQ(executive.status().recoveries(), 0u);
    EXPECT_TRUE(executive.takeOutbox().events.empty());
  }
}

TEST_F(MissionRecoveryTest, NoRecoveriesAllowedAbortsAsBefore) {
  ExecutiveOptions options = recoveryOptions();
  options.max_recoveries = 0;
  executive = MissionExecutive(options);
  startReady({query({10, 0, 5})});
  follow(waypoint({4, 0, 5}));
  controller(/*safety=*/true);
  EXPECT_EQ(state(), msg::MISSION_STATE_ABORTED);
  EXPECT_CONTAINS(message(), "controller safety manoeuvre MIN_ALTITUDE");
}

TEST_F(MissionRecoveryTest, ManoeuvreAgainWhileHoldingWaitsForItToEnd) {
  startReady({query({10, 0, 5})});
  follow(waypoint({4, 0, 5}));
  interruptFor(2.0);  // holding now
  manoeuvre = true;   // it fires again before the re-issue
  advance(10.0);
  EXPECT_TRUE(executive.takeOutbox().queries.empty());
  EXPECT_EQ(state(), msg::MISSION_STATE_RECOVERING);
  manoeuvre = false;
  advance(1.0);  // over again: a new hold
  auto out = executive.takeOutbox();
  ASSERT_EQ(out.commands.size(), 1u);
  EXPECT_EQ(out.commands[0].mode(), msg::CONTROL_MODE_HOLD);
  advance(5.5);
  EXPECT_EQ(executive.takeOutbox().queries.size(), 1u);
  EXPECT_EQ(executive.status().recoveries(), 1u);  // one interruption, one re-issue
}

TEST_F(MissionRecoveryTest, NavigationLostManoeuvreWaitsForNavigationToReturn) {
  startReady({query({10, 0, 5})});
  follow(waypoint({4, 0, 5}));
  safety_reason = msg::SAFETY_REASON_NAVIGATION_LOST;
  controller(/*safety=*/true);
  ASSERT_EQ(state(), msg::MISSION_STATE_RECOVERING);
  // Navigation silent: stale, but the recovery waits instead of aborting.
  for (int i = 0; i < 10; ++i) {
    t += 1.0;
    controller(/*safety=*/true);
    executive.tick(t);
  }
  EXPECT_EQ(state(), msg::MISSION_STATE_RECOVERING) << message();
  manoeuvre = false;
  advance(1.0);  // navigation back, manoeuvre over: hold
  advance(5.5);
  EXPECT_EQ(executive.takeOutbox().queries.size(), 1u);
  EXPECT_EQ(state(), msg::MISSION_STATE_WAITING_FOR_WAYPOINT);
}

}  // namespace
}  // namespace auv::mission
