// The low-level controller in closed loop with the vehicle dynamics (ground-truth navigation).
#include "auv/control/controller.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "closed_loop.h"

namespace auv::control {
namespace {
using namespace test_support;

TEST(LowLevelControllerTest, WaypointIsReachedAndHeld) {
  ClosedLoop loop;
  loop.state.position = {0, 0, 2};
  const Eigen::Vector3d target(25, 12, 4);
  ASSERT_TRUE(loop.send(waypoint(1, target)).accepted());
  EXPECT_EQ(loop.status().state, ControllerState::ACTIVE);
  EXPECT_EQ(loop.status().distance_to_target, -1.0);  // no navigation yet
  loop.run(kDt);
  EXPECT_NEAR(loop.status().distance_to_target, (target - loop.state.position).norm(), 0.01);
  double top_speed = 0;
  const double took = loop.runUntil(
      [&] {
        top_speed = std::max(top_speed, loop.state.surge);
        return loop.status().reached;
      },
      120);
  ASSERT_TRUE(loop.status().reached) << "distance " << loop.status().distance_to_target;
  // 27.8 m at up to 0.8 m/s, plus turning and slowing down: well under two minutes.
  EXPECT_GT(took, 27.8 / 0.8);
  EXPECT_LT(took, 80);
  EXPECT_NEAR(top_speed, 0.8, 0.08);  // cruised at the commanded speed
  EXPECT_EQ(loop.status().state, ControllerState::HOLDING);
  EXPECT_EQ(loop.status().active_command_id, 1u);
  EXPECT_LE((target - loop.state.position).norm(), 1.0);
  // Held: stays near the target and at its depth, and the status keeps saying reached.
  double worst = 0;
  loop.run(30, [&] { worst = std::max(worst, horizontalDistance(loop.state, target)); });
  EXPECT_LT(worst, 1.5);
  EXPECT_NEAR(loop.state.position.z(), 4.0, 0.05);
  EXPECT_NEAR(loop.state.surge, 0.0, 0.05);
  EXPECT_TRUE(loop.status().reached);
  EXPECT_EQ(loop.status().state, ControllerState::HOLDING);
}

TEST(LowLevelControllerTest, DepthChangesAlongTheLegNotBeforeIt) {
  // A climb of 3 m over 15 m (11 deg, as the planner checks it): flown along the straight leg,
  // not as a climb on the spot and a level run after it (under an overhang the first would
  // rise into rock above the leg). Depth mode; the vehicle starts pointing at the target.
  ClosedLoop loop;
  loop.state.position = {0, 0, 6};
  const Eigen::Vector3d start = loop.state.position, target(15, 0, 3);
  ASSERT_TRUE(loop.send(waypoint(1, target)).accepted());
  double worst = 0, shallowest_early = 10;
  loop.runUntil(
      [&] {
        const double progress = std::clamp(loop.state.position.x() / target.x(), 0.0, 1.0);
        const double leg_depth = start.z() + progress * (target.z() - start.z());
        worst = std::max(worst, std::abs(loop.state.position.z() - leg_depth));
        if (loop.state.position.x() < 3.0)
          shallowest_early = std::min(shallowest_early, loop.state.position.z());
        return loop.status().reached;
      },
      120);
  ASSERT_TRUE(loop.status().reached);
  EXPECT_LT(worst, 0.4);             // on the leg within decimetres
  EXPECT_GT(shallowest_early, 4.6);  // the first 3 m climb about 1 m (0.6 m + the lead), not 3
  loop.run(10);
  EXPECT_NEAR(loop.state.position.z(), 3.0, 0.1);
}

TEST(LowLevelControllerTest, WaypointBehindTurnsAroundFirst) {
  ClosedLoop loop;
  loop.state.position = {0, 0, 3};
  const Eigen::Vector3d target(-15, 1, 3);
  ASSERT_TRUE(loop.send(waypoint(4, target, 0.6, 0.5)).accepted());
  double most_ahead = 0;  // how far north it drifted while turning to the south
  loop.runUntil(
      [&] {
        most_ahead = std::max(most_ahead, loop.state.position.x());
        return loop.status().reached;
      },
      120);
  ASSERT_TRUE(loop.status().reached);
  EXPECT_LT(most_ahead, 1.0);
  EXPECT_LE((target - loop.state.position).norm(), 0.5);
}

// Going north at 0.3 m/s (the speed near waypoints), then a waypoint 4 m behind (a planner
// turning back in a narrow passage): the sideways swing of the turn is what a passage must
// have room for.
double sidewaysSwingOfAUTurn(double turn_in_place_angle) {
  ControllerOptions options;
  options.turn_in_place_angle = turn_in_place_angle;
  ClosedLoop loop(options);
  loop.state.position = {0, 0, 2};
  EXPECT_TRUE(loop.send(waypoint(1, {30, 0, 2}, 0.3)).accepted());
  loop.run(20);
  const Eigen::Vector3d turn_start = loop.state.position;
  EXPECT_TRUE(loop.send(waypoint(2, turn_start - Eigen::Vector3d(4, 0, 0), 0.3, 0.5)).accepted());
  double swing = 0;
  loop.runUntil(
      [&] {
        swing = std::max(swing, std::abs(loop.state.position.y() - turn_start.y()));
        return loop.status().reached;
      },
      60);
  EXPECT_TRUE(loop.status().reached);
  return swing;
}

TEST(LowLevelControllerTest, TurningRoundOnTheSpotSwingsLessSideways) {
  const double on_the_spot = sidewaysSwingOfAUTurn(M_PI / 6);
  const double cosine = sidewaysSwingOfAUTurn(M_PI / 2);
  EXPECT_LT(on_the_spot, 0.6 * cosine) << "cos(error) speed swung " << cosine << " m";
}

TEST(LowLevelControllerTest, HeadingStepSettlesWithoutLargeOvershoot) {
  ClosedLoop loop;
  loop.state.position = {0, 0, 3};
  ASSERT_TRUE(loop.send(setpoint(1, M_PI / 2, 3, 0.0)).accepted());
  double peak = 0;
  loop.run(30, [&] { peak = std::max(peak, loop.state.yaw); });
  EXPECT_LT(peak - M_PI / 2, 0.1);  // < 6 degrees of overshoot
  EXPECT_NEAR(loop.state.yaw, M_PI / 2, 0.02);
  EXPECT_NEAR(loop.state.yaw_rate, 0.0, 0.01);
  // Settled within 20 s: stays within 2 degrees from then on.
  double worst = 0;
  loop.run(10, [&] { worst = std::max(worst, std::abs(loop.state.yaw - M_PI / 2)); });
  EXPECT_LT(worst, 0.035);
}

TEST(LowLevelControllerTest, HeadingTakesTheShortWayAcrossPi) {
  ClosedLoop loop;
  loop.state.position = {0, 0, 3};
  loop.state.yaw = 170.0 * M_PI / 180;
  ASSERT_TRUE(loop.send(setpoint(1, -170.0 * M_PI / 180, 3, 0.0)).accepted());
  double furthest_back = 0;  // any turn the long way passes through yaw ~ 0
  loop.run(25, [&] {
    furthest_back = std::max(furthest_back, std::abs(wrapAngle(loop.state.yaw - M_PI)));
  });
  EXPECT_LT(furthest_back, 0.3);  // never more than ~17 degrees from south
  EXPECT_NEAR(wrapAngle(loop.state.yaw + 170.0 * M_PI / 180), 0.0, 0.02);
}

TEST(LowLevelControllerTest, DepthIsHeldWithinCentimetresWhileCruising) {
  ClosedLoop loop;
  loop.state.position = {0, 0, 1};
  ASSERT_TRUE(loop.send(setpoint(1, 0.3, 5.0, 0.8)).accepted());
  loop.run(40);
  double worst = 0;
  loop.run(30, [&] { worst = std::max(worst, std::abs(loop.state.position.z() - 5.0)); });
  EXPECT_LT(worst, 0.03);
  EXPECT_NEAR(loop.state.surge, 0.8, 0.02);
  EXPECT_NEAR(loop.state.yaw, 0.3, 0.02);
}

TEST(LowLevelControllerTest, IntegralActionRemovesAWrongBuoyancyModel) {
  VehicleModel heavy_truth;
  heavy_truth.net_buoyancy = 6.0;  // the controller's model still thinks 2 N
  ClosedLoop loop({}, heavy_truth);
  loop.state.position = {0, 0, 3};
  ASSERT_TRUE(loop.send(setpoint(1, 0.0, 3.0, 0.5)).accepted());
  loop.run(60);
  EXPECT_NEAR(loop.state.position.z(), 3.0, 0.03);
  // Without the integral, proportional action alone would leave (6 - 2) / kp = 0.16 m.
  ControllerOptions proportional;
  proportional.depth_ki = 0.0;
  ClosedLoop p_only(proportional, heavy_truth);
  p_only.state.position = {0, 0, 3};
  ASSERT_TRUE(p_only.send(setpoint(1, 0.0, 3.0, 0.5)).accepted());
  p_only.run(60);
  EXPECT_NEAR(p_only.state.position.z(), 3.0 - 4.0 / proportional.depth_kp, 0.02);
}

// Cruises 30 s at 3 m depth and `speed`, then the DVL loses lock: from then on `hold` writes
// the filter's held velocity into the estimate, flagged as held (not measured) if `flagged`.
void cruiseThenLoseDvlLock(ClosedLoop& loop, double speed, bool flagged,
                           std::function<void(ControllerNavigation&)> hold) {
  loop.state.position = {0, 0, 3};
  EXPECT_TRUE(loop.send(setpoint(1, 0.0, 3.0, speed)).accepted());
  loop.run(30);
  loop.filter = [flagged, hold](ControllerNavigation& nav) {
    hold(nav);
    nav.velocity_measured = !flagged;
  };
}

TEST(LowLevelControllerTest, HeldVelocityWithoutDvlLockDoesNotDriveTheVehicleOff) {
  // Cruising at 0.8 m/s, the DVL loses lock: the filter holds 0.8 m/s while the vehicle is
  // asked to slow to 0.2 m/s.
  auto slowDownWithHeldVelocity = [](bool flagged) {
    ClosedLoop loop;
    cruiseThenLoseDvlLock(loop, 0.8, flagged, [](ControllerNavigation& nav) { nav.surge = 0.8; });
    EXPECT_TRUE(loop.send(setpoint(2, 0.0, 3.0, 0.2)).accepted());
    loop.run(20);
    return loop.state.surge;
  };
  // Flagged: feed-forward alone brings it to the asked speed.
  EXPECT_NEAR(slowDownWithHeldVelocity(true), 0.2, 0.05);
  // Unflagged, the loop would brake against a speed that never drops: the vehicle reverses.
  EXPECT_LT(slowDownWithHeldVelocity(false), -0.2);
}

TEST(LowLevelControllerTest, HeldHeaveWithoutDvlLockDoesNotPushTheVehicleOffItsDepth) {
  // Holding 3 m, the DVL loses lock while the filter holds 0.2 m/s of heave (down): the depth
  // itself is still measured.
  auto worstDepthErrorWithHeldHeave = [](bool flagged) {
    ClosedLoop loop;
    cruiseThenLoseDvlLock(loop, 0.5, flagged, [](ControllerNavigation& nav) { nav.heave = 0.2; });
    double worst = 0;
    loop.run(20, [&] { worst = std::max(worst, std::abs(loop.state.position.z() - 3.0)); });
    return worst;
  };
  // Flagged: damped by the depth's own rate, it stays within centimetres.
  EXPECT_LT(worstDepthErrorWithHeldHeave(true), 0.05);
  // Unflagged, the damping pushes up against a descent that is not happening: kd / kp * 0.2 m/s
  // = 0.4 m above the asked depth (the integral is frozen while the heave looks large).
  EXPECT_GT(worstDepthErrorWithHeldHeave(false), 0.3);
}

TEST(LowLevelControllerTest, MaxDepthRaisesTheSafetyManoeuvreUntilCleared) {
  ControllerOptions options;
  options.max_depth = 10.0;
  ClosedLoop loop(options);
  loop.state.position = {0, 0, 10.6};
  ASSERT_TRUE(loop.send(setpoint(3, 0.0, 9.0, 0.5)).accepted());
  loop.run(kDt);
  EXPECT_EQ(loop.status().state, ControllerState::SAFETY_MANEUVER);
  EXPECT_TRUE(loop.status().safety_maneuver);
  EXPECT_EQ(loop.status().safety_reason, SafetyReason::MAX_DEPTH);
  EXPECT_NE(loop.status().safety_text.find("max_depth 10"), std::string::npos)
      << loop.status().safety_text;
  EXPECT_EQ(loop.last.vertical, -1.0);
  EXPECT_EQ(loop.last.port, 0.0);
  // Commands are refused during the manoeuvre.
  EXPECT_EQ(loop.send(setpoint(4, 0.0, 5.0, 0.5)).outcome, CommandResult::Outcome::REFUSED);
  // It rises above max_depth, stays in the manoeuvre for safety_clear_time, then goes IDLE.
  const double rise = loop.runUntil([&] { return loop.state.position.z() < 10.0; }, 30);
  EXPECT_LT(rise, 10);
  EXPECT_TRUE(loop.status().safety_maneuver);
  const double cleared = loop.runUntil([&] { return !loop.status().safety_maneuver; }, 30);
  EXPECT_NEAR(cleared, options.safety_clear_time, 2 * kDt);
  EXPECT_EQ(loop.status().state, ControllerState::IDLE);
  EXPECT_EQ(loop.status().safety_reason, SafetyReason::NONE);
  EXPECT_EQ(loop.status().active_command_id, 3u);
  EXPECT_FALSE(loop.status().reached);
  EXPECT_LT(loop.state.position.z(), 10.0);
  // The interrupted command is dropped: thrusters off until a new one arrives.
  loop.run(1);
  EXPECT_EQ(loop.last.vertical, 0.0);
  EXPECT_TRUE(loop.send(setpoint(5, 0.0, 5.0, 0.5)).accepted());
  EXPECT_EQ(loop.status().state, ControllerState::ACTIVE);
}

TEST(LowLevelControllerTest, MinAltitudeStopsTheDescentOverTheSeabed) {
  ClosedLoop loop;  // min_altitude 1 m
  loop.seabed_depth = 12.0;
  loop.state.position = {0, 0, 8};
  ASSERT_TRUE(loop.send(setpoint(1, 0.0, 11.6, 0.3)).accepted());  // 0.4 m above the seabed
  double deepest = 0;
  bool raised = false;
  loop.run(40, [&] {
    deepest = std::max(deepest, loop.state.position.z());
    if (loop.status().safety_maneuver) {
      raised = true;
      EXPECT_EQ(loop.status().safety_reason, SafetyReason::MIN_ALTITUDE);
    }
  });
  ASSERT_TRUE(raised);
  EXPECT_GT(deepest, 11.0);  // it did cross min_altitude...
  EXPECT_LT(deepest, 11.4);  // ...and turned back well before the seabed
  EXPECT_EQ(loop.status().state, ControllerState::IDLE);  // cleared, command dropped
}

TEST(LowLevelControllerTest, UnknownAltitudeNeverTriggersMinAltitude) {
  ClosedLoop loop;  // altitude -1
  loop.state.position = {0, 0, 8};
  ASSERT_TRUE(loop.send(setpoint(1, 0.0, 11.6, 0.3)).accepted());
  loop.run(40, [&] { ASSERT_FALSE(loop.status().safety_maneuver); });
  EXPECT_NEAR(loop.state.position.z(), 11.6, 0.05);
}

TEST(LowLevelControllerTest, LostNavigationRaisesTheManoeuvreAfterTheTimeout) {
  ClosedLoop loop;  // navigation_timeout 1 s
  loop.state.position = {0, 0, 5};
  ASSERT_TRUE(loop.send(waypoint(9, {50, 0, 5})).accepted());
  loop.run(5);
  EXPECT_EQ(loop.status().state, ControllerState::ACTIVE);
  // Silence: nothing for up to the timeout, then the manoeuvre.
  loop.run(
      0.9, [&] { ASSERT_FALSE(loop.status().safety_maneuver); }, false);
  loop.run(0.2, {}, false);
  EXPECT_EQ(loop.status().state, ControllerState::SAFETY_MANEUVER);
  EXPECT_EQ(loop.status().safety_reason, SafetyReason::NAVIGATION_LOST);
  EXPECT_NE(loop.status().safety_text.find("navigation_timeout"), std::string::npos);
  EXPECT_EQ(loop.last.vertical, -1.0);
  EXPECT_EQ(loop.last.port, 0.0);
  EXPECT_EQ(loop.last.starboard, 0.0);
  // Broken estimates do not count as navigation.
  ControllerNavigation broken = ControllerNavigation::fromState(loop.state, -1, loop.t);
  broken.yaw = std::nan("");
  EXPECT_FALSE(loop.controller.setNavigation(broken, loop.t));
  loop.run(5, {}, false);
  EXPECT_EQ(loop.status().safety_reason, SafetyReason::NAVIGATION_LOST);
  // Navigation back: clears after safety_clear_time.
  loop.run(3.5);
  EXPECT_FALSE(loop.status().safety_maneuver);
  EXPECT_EQ(loop.status().state, ControllerState::IDLE);
}

TEST(LowLevelControllerTest, NoNavigationAtAllIsNavigationLost) {
  ClosedLoop loop;
  loop.run(0.9, {}, false);
  EXPECT_FALSE(loop.status().safety_maneuver);
  loop.run(0.2, {}, false);
  EXPECT_EQ(loop.status().safety_reason, SafetyReason::NAVIGATION_LOST);
}

TEST(LowLevelControllerTest, CommandTimeoutIsAFaultNotReached) {
  ClosedLoop loop;
  loop.state.position = {0, 0, 4};
  ControlCommand far = waypoint(2, {200, 0, 4});
  far.timeout = 10.0;
  ASSERT_TRUE(loop.send(far).accepted());
  loop.run(9.9);
  EXPECT_EQ(loop.status().state, ControllerState::ACTIVE);
  loop.run(0.2);
  EXPECT_EQ(loop.status().state, ControllerState::FAULT);
  EXPECT_FALSE(loop.status().reached);
  EXPECT_FALSE(loop.status().safety_maneuver);
  EXPECT_EQ(loop.status().active_command_id, 2u);
  // Default fault action: horizontal thrusters off, depth kept.
  loop.run(30);
  EXPECT_EQ(loop.last.port, 0.0);
  EXPECT_EQ(loop.last.starboard, 0.0);
  EXPECT_NEAR(loop.state.position.z(), 4.0, 0.1);
  EXPECT_NEAR(loop.state.surge, 0.0, 0.1);
}

TEST(LowLevelControllerTest, MalformedCommandsAreRejectedNamingTheField) {
  ClosedLoop loop;
  loop.state.position = {0, 0, 2};
  ASSERT_TRUE(loop.send(waypoint(1, {10, 0, 2})).accepted());
  auto rejected = [&](ControlCommand c, const std::string& field) {
    const CommandResult r = loop.send(c);
    EXPECT_EQ(r.outcome, CommandResult::Outcome::REJECTED) << field;
    EXPECT_NE(r.reason.find(field + ":"), std::string::npos) << r.reason;
  };
  ControlCommand c = waypoint(2, {10, 0, 2});
  c.surge_speed = std::nan("");
  rejected(c, "surge_speed");
  c = waypoint(2, {10, std::numeric_limits<double>::infinity(), 2});
  rejected(c, "position.y");
  c = waypoint(2, {10, 0, 2}, 0.5, -1.0);
  rejected(c, "tolerance");
  c = waypoint(2, {10, 0, -3});
  rejected(c, "position.z");
  c = waypoint(2, {10, 0, 2});
  c.mode = static_cast<ControlMode>(17);
  rejected(c, "mode");
  c = waypoint(0, {10, 0, 2});
  rejected(c, "command_id");
  c = setpoint(2, 0.0, 2.0, 3.0);
  rejected(c, "surge_speed");
  c = setpoint(2, 0.0, 80.0, 0.5);
  rejected(c, "depth");
  // The previous command is still the active one and still executed.
  EXPECT_EQ(loop.status().active_command_id, 1u);
  EXPECT_EQ(loop.controller.command().mode, ControlMode::WAYPOINT);
  loop.run(60);
  EXPECT_TRUE(loop.status().reached);
  // A repeated id and mode NONE are ignored, not errors.
  EXPECT_EQ(loop.send(waypoint(1, {10, 0, 2})).outcome, CommandResult::Outcome::IGNORED);
  ControlCommand none;
  none.command_id = 3;
  EXPECT_EQ(loop.send(none).outcome, CommandResult::Outcome::IGNORED);
  EXPECT_EQ(loop.status().state, ControllerState::HOLDING);
}

TEST(LowLevelControllerTest, DefaultsFillZeroSpeedAndTolerance) {
  ClosedLoop loop;
  loop.state.position = {0, 0, 2};
  ASSERT_TRUE(loop.send(waypoint(1, {30, 0, 2}, 0.0, 0.0)).accepted());
  EXPECT_EQ(loop.controller.command().surge_speed, ControllerOptions().default_surge_speed);
  EXPECT_EQ(loop.controller.command().tolerance, ControllerOptions().default_tolerance);
  loop.runUntil([&] { return loop.status().reached; }, 90);
  EXPECT_TRUE(loop.status().reached);
}

TEST(LowLevelControllerTest, StopSurfaceAndHold) {
  ClosedLoop loop;
  loop.state.position = {0, 0, 5};
  ASSERT_TRUE(loop.send(setpoint(1, 0.0, 5.0, 0.8)).accepted());
  loop.run(20);
  ControlCommand stop;
  stop.command_id = 2;
  stop.mode = ControlMode::STOP;
  ASSERT_TRUE(loop.send(stop).accepted());
  loop.run(kDt);
  EXPECT_EQ(loop.status().state, ControllerState::IDLE);
  EXPECT_EQ(loop.status().active_command_id, 2u);
  EXPECT_EQ(loop.last.port, 0.0);
  EXPECT_EQ(loop.last.vertical, 0.0);

  ControlCommand hold;
  hold.command_id = 3;
  hold.mode = ControlMode::HOLD;
  ASSERT_TRUE(loop.send(hold).accepted());
  const Eigen::Vector3d held = loop.state.position;
  EXPECT_EQ(loop.status().state, ControllerState::HOLDING);
  loop.run(40);
  // The vehicle coasted on after the stop; HOLD brings it back within the default radius.
  EXPECT_LT(horizontalDistance(loop.state, held), ControllerOptions().default_tolerance + 0.2);
  EXPECT_NEAR(loop.state.position.z(), held.z(), 0.05);

  ControlCommand surface;
  surface.command_id = 4;
  surface.mode = ControlMode::SURFACE;
  ASSERT_TRUE(loop.send(surface).accepted());
  loop.runUntil([&] { return loop.status().reached; }, 60);
  EXPECT_TRUE(loop.status().reached);
  EXPECT_LE(loop.state.position.z(), ControllerOptions().surface_depth);
  loop.run(10);
  EXPECT_EQ(loop.state.position.z(), 0.0);  // buoyancy keeps it there
}

TEST(LowLevelControllerTest, OptionsCheckNamesTheField) {
  ControllerOptions options;
  options.depth_kp = -1;
  try {
    LowLevelController controller(options);
    FAIL() << "negative gain accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("controller.depth_kp"), std::string::npos) << e.what();
  }
  options = ControllerOptions();
  options.model.max_thrust_forward = 0;
  try {
    options.check();
    FAIL() << "zero thrust accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("controller.model.max_thrust_forward"), std::string::npos)
        << e.what();
  }
}

TEST(LowLevelControllerTest, StatusChangeDetectionIgnoresMeasurements) {
  ControllerStatusReport a, b;
  b.depth = 3;
  b.distance_to_target = 7;
  EXPECT_FALSE(a.differsInState(b));
  b.reached = true;
  EXPECT_TRUE(a.differsInState(b));
}

}  // namespace
}  // namespace auv::control
