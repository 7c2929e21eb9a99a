// Safety manoeuvres under rock (the overhead probe), the breadcrumb trail and the altitude mode,
// closed on the vehicle dynamics.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "auv/control/controller.h"
#include "closed_loop.h"

namespace auv::control {
namespace {
using namespace test_support;

constexpr double kOpen = std::numeric_limits<double>::infinity();

// A roof of rock at `roof_depth` over the water where `covered(position)` holds.
OverheadProbe roof(double roof_depth, std::function<bool(const Eigen::Vector3d&)> covered) {
  return [=](const Eigen::Vector3d& p) { return covered(p) ? p.z() - roof_depth : kOpen; };
}

// Distance from p (horizontally) to the segment a-b.
double distanceToSegment(const Eigen::Vector3d& p, const Eigen::Vector2d& a,
                         const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double t = std::clamp((p.head<2>() - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (p.head<2>() - (a + t * ab)).norm();
}

// Drives the L-shaped track (0,0) -> (20,0) -> (20,15) at `depth`.
void driveTheL(ClosedLoop& loop, double depth) {
  loop.state.position = {0, 0, depth};
  ASSERT_TRUE(loop.send(waypoint(1, {20, 0, depth})).accepted());
  loop.runUntil([&] { return loop.status().reached; }, 120);
  ASSERT_TRUE(loop.status().reached);
  ASSERT_TRUE(loop.send(waypoint(2, {20, 15, depth})).accepted());
  loop.runUntil([&] { return loop.status().reached; }, 120);
  ASSERT_TRUE(loop.status().reached);
}

TEST(ControllerSafetyTest, MinAltitudeUnderOpenWaterAscends) {
  ClosedLoop loop;
  loop.controller.setOverheadProbe([](const Eigen::Vector3d&) { return kOpen; });
  bool low = false;
  loop.filter = [&](ControllerNavigation& nav) { nav.altitude = low ? 0.5 : 5.0; };
  driveTheL(loop, 7.0);
  low = true;
  loop.run(kDt);
  ASSERT_EQ(loop.status().safety_reason, SafetyReason::MIN_ALTITUDE);
  EXPECT_EQ(loop.last.vertical, -1.0);
  EXPECT_EQ(loop.last.port, 0.0);
  EXPECT_NE(loop.status().safety_text.find("; ascending"), std::string::npos)
      << loop.status().safety_text;
  const double rise = loop.runUntil([&] { return loop.state.position.z() < 4.0; }, 60);
  EXPECT_LT(rise, 60);  // on its way up
}

TEST(ControllerSafetyTest, MinAltitudeUnderRockBacksAwayAlongTheTrackThenAscends) {
  ClosedLoop loop;
  // Rock 3 m above everywhere east of x = 10: the whole second leg and half the first.
  loop.controller.setOverheadProbe(
      roof(4.0, [](const Eigen::Vector3d& p) { return p.x() > 10.0; }));
  bool low = false;  // then the DVL sees rock 0.5 m below, all along the way back
  loop.filter = [&](ControllerNavigation& nav) { nav.altitude = low ? 0.5 : 5.0; };
  driveTheL(loop, 7.0);
  const double start_depth = loop.state.position.z();
  ASSERT_GE(loop.controller.trail().size(), 25u);
  low = true;
  loop.run(kDt);
  ASSERT_EQ(loop.status().safety_reason, SafetyReason::MIN_ALTITUDE);
  EXPECT_NE(loop.status().safety_text.find("backing away: rock 3.0 m above"), std::string::npos)
      << loop.status().safety_text;
  EXPECT_EQ(loop.status().safety_action, "backing away");

  double shallowest_under_rock = start_depth;
  double off_track = 0.0;
  bool reversed = false;
  const double took = loop.runUntil(
      [&] {
        const Eigen::Vector3d& p = loop.state.position;
        if (p.x() > 10.0) {
          shallowest_under_rock = std::min(shallowest_under_rock, p.z());
          off_track = std::max(off_track, std::min(distanceToSegment(p, {0, 0}, {20, 0}),
                                                   distanceToSegment(p, {20, 0}, {20, 15})));
        }
        reversed = reversed || loop.state.surge < -0.1;
        return p.x() <= 10.0 && p.z() < start_depth - 2.0;
      },
      400);
  ASSERT_LT(took, 400) << "at " << loop.state.position.transpose() << ": "
                       << loop.status().safety_text;
  // Never up into the rock: the depth held under it within centimetres.
  EXPECT_GT(shallowest_under_rock, start_depth - 0.05);
  // Back the way it came: up the second leg, round the corner, along the first.
  EXPECT_LT(off_track, 1.5);
  EXPECT_TRUE(reversed);
  EXPECT_NE(loop.status().safety_text.find("; ascending"), std::string::npos)
      << loop.status().safety_text;
  EXPECT_EQ(loop.status().safety_action, "ascending");
}

TEST(ControllerSafetyTest, TrailUsedUpHoldsPositionAndDepth) {
  ControllerOptions options;
  options.breadcrumb_length = 3.0;  // a short trail, still under the rock at its end
  ClosedLoop loop(options);
  loop.controller.setOverheadProbe(roof(4.0, [](const Eigen::Vector3d&) { return true; }));
  bool low = false;
  loop.filter = [&](ControllerNavigation& nav) { nav.altitude = low ? 0.5 : 5.0; };
  driveTheL(loop, 7.0);
  low = true;
  loop.run(60);
  EXPECT_EQ(loop.status().safety_reason, SafetyReason::MIN_ALTITUDE);
  EXPECT_NE(loop.status().safety_text.find("no trail left"), std::string::npos)
      << loop.status().safety_text;
  EXPECT_NEAR(loop.state.position.z(), 7.0, 0.1);
  EXPECT_GT(loop.state.position.y(), 10.0);  // backed at most the 3 m trail (and its drift)
  EXPECT_NEAR(loop.state.surge, 0.0, 0.05);
}

TEST(ControllerSafetyTest, ConditionClearedUnderRockEndsTheManoeuvreWithoutAscending) {
  ClosedLoop loop;
  loop.controller.setOverheadProbe(roof(4.0, [](const Eigen::Vector3d&) { return true; }));
  // Then a ledge 0.6 m under the vehicle's depth along the last 2 m of the second leg.
  bool ledge = false;
  loop.filter = [&](ControllerNavigation& nav) {
    nav.altitude = ledge && nav.position.y() > 13.0 ? 0.6 : 5.0;
  };
  driveTheL(loop, 7.0);
  ledge = true;
  double shallowest = loop.state.position.z();
  bool raised = false;
  loop.run(40, [&] {
    shallowest = std::min(shallowest, loop.state.position.z());
    raised = raised || loop.status().safety_maneuver;
  });
  EXPECT_TRUE(raised);
  EXPECT_FALSE(loop.status().safety_maneuver);
  EXPECT_EQ(loop.status().state, ControllerState::HOLDING);  // under the rock: holds there
  EXPECT_LT(loop.state.position.y(), 13.0);                  // backed off the ledge
  EXPECT_GT(shallowest, 6.95);
  EXPECT_NEAR(loop.state.position.z(), 7.0, 0.1);
}

TEST(ControllerSafetyTest, NavigationLostUnderRockHoldsWithoutAscending) {
  ClosedLoop loop;
  loop.controller.setOverheadProbe(roof(4.0, [](const Eigen::Vector3d&) { return true; }));
  loop.state.position = {0, 0, 7};
  ASSERT_TRUE(loop.send(setpoint(1, 0.0, 7.0, 0.0)).accepted());
  loop.run(10);
  loop.run(1.5, {}, /*navigation=*/false);
  ASSERT_EQ(loop.status().safety_reason, SafetyReason::NAVIGATION_LOST);
  EXPECT_NE(loop.status().safety_text.find("holding: rock 3.0 m above"), std::string::npos)
      << loop.status().safety_text;
  EXPECT_EQ(loop.last.port, 0.0);
  EXPECT_EQ(loop.last.starboard, 0.0);
  EXPECT_GT(loop.last.vertical, 0.0);  // down, against the buoyancy only
  EXPECT_LT(loop.last.vertical, 0.5);
  loop.run(20, {}, false);
  EXPECT_NEAR(loop.state.position.z(), 7.0, 0.1);
}

TEST(ControllerSafetyTest, MaxDepthUnderRockRisesButStaysBelowIt) {
  ControllerOptions options;
  options.max_depth = 10.0;
  ClosedLoop loop(options);
  // Rock at 8.6 m above the vehicle: a little above max_depth is 9 m, 0.5 m below the rock 9.1 m.
  loop.controller.setOverheadProbe(roof(8.6, [](const Eigen::Vector3d&) { return true; }));
  loop.state.position = {0, 0, 10.6};
  ASSERT_TRUE(loop.send(setpoint(3, 0.0, 9.5, 0.5)).accepted());
  double shallowest = loop.state.position.z();
  loop.run(30, [&] { shallowest = std::min(shallowest, loop.state.position.z()); });
  EXPECT_FALSE(loop.status().safety_maneuver);  // back above max_depth: cleared
  EXPECT_LT(loop.state.position.z(), 10.0);
  EXPECT_GT(shallowest, 8.9);  // never up into the rock, nor after: it holds under it
  EXPECT_EQ(loop.status().state, ControllerState::HOLDING);
}

TEST(ControllerSafetyTest, AltitudeModeFollowsASlope) {
  ClosedLoop loop;
  // The seabed rises 1 m in 5 northwards, from 20 m; the DVL measures it with noise.
  std::mt19937 random(7);
  std::normal_distribution<double> noise(0.0, 0.1);
  auto seabed = [](double x) { return 20.0 - 0.2 * x; };
  loop.filter = [&](ControllerNavigation& nav) {
    nav.altitude = seabed(nav.position.x()) - nav.position.z() + noise(random);
  };
  loop.state.position = {0, 0, 12};
  ControlCommand c = setpoint(1, 0.0, 25.0, 0.5);  // deepest 25 m
  c.altitude = 3.0;
  ASSERT_TRUE(loop.send(c).accepted());
  loop.run(30);  // settles at 3 m above the seabed
  double lowest = 100, highest = 0;
  loop.run(40, [&] {
    const double altitude = seabed(loop.state.position.x()) - loop.state.position.z();
    lowest = std::min(lowest, altitude);
    highest = std::max(highest, altitude);
    ASSERT_FALSE(loop.status().safety_maneuver);
  });
  EXPECT_GT(loop.state.position.x(), 20.0);  // crossed 4 m of rise
  // Within half a metre (noise 0.1 m, low-pass lag on the slope); in depth mode it would have
  // gone from 8 m to 4 m above the seabed.
  EXPECT_GT(lowest, 2.5 - 0.1);
  EXPECT_LT(highest, 3.5);

  // Never deeper than the commanded depth: over deeper water it stays at 14 m.
  ControlCommand shallow = setpoint(2, M_PI, 14.0, 0.5);
  shallow.altitude = 3.0;
  ASSERT_TRUE(loop.send(shallow).accepted());
  loop.run(90);
  EXPECT_LT(loop.state.position.x(), 5.0);  // back over 19+ m of water
  EXPECT_NEAR(loop.state.position.z(), 14.0, 0.1);
}

TEST(ControllerSafetyTest, AltitudeModeWithoutBottomLockKeepsTheDepthItHas) {
  ClosedLoop loop;  // altitude unknown (-1)
  loop.state.position = {0, 0, 6};
  ControlCommand c = setpoint(1, 0.0, 15.0, 0.3);
  c.altitude = 2.0;
  ASSERT_TRUE(loop.send(c).accepted());
  loop.run(30);
  EXPECT_NEAR(loop.state.position.z(), 6.0, 0.1);  // not down blind to 15 m
}

TEST(ControllerSafetyTest, WaypointAtAnotherDepthIsReached) {
  ClosedLoop loop;
  loop.state.position = {0, 0, 2};
  ASSERT_TRUE(loop.send(waypoint(1, {15, 5, 9})).accepted());
  loop.runUntil([&] { return loop.status().reached; }, 120);
  ASSERT_TRUE(loop.status().reached);
  ASSERT_TRUE(loop.send(waypoint(2, {30, 5, 3})).accepted());
  loop.runUntil([&] { return loop.status().reached; }, 120);
  ASSERT_TRUE(loop.status().reached);
  loop.run(10);
  EXPECT_NEAR(loop.state.position.z(), 3.0, 0.1);
}

TEST(ControllerSafetyTest, BadAltitudeIsRejectedNamingTheField) {
  ClosedLoop loop;
  ControlCommand c = setpoint(1, 0.0, 5.0, 0.3);
  c.altitude = -1.0;
  CommandResult r = loop.send(c);
  EXPECT_EQ(r.outcome, CommandResult::Outcome::REJECTED);
  EXPECT_NE(r.reason.find("altitude:"), std::string::npos) << r.reason;
  c.altitude = std::nan("");
  r = loop.send(c);
  EXPECT_EQ(r.outcome, CommandResult::Outcome::REJECTED);
  EXPECT_NE(r.reason.find("altitude:"), std::string::npos) << r.reason;
}

TEST(ControllerSafetyTest, TrailKeepsTheRecentPositionsOnly) {
  ClosedLoop loop;
  driveTheL(loop, 5.0);
  const auto& trail = loop.controller.trail();
  ASSERT_GE(trail.size(), 2u);
  EXPECT_EQ(trail.size(), 31u);  // full: 30 m at 1 m spacing
  for (size_t i = 1; i < trail.size(); ++i) EXPECT_GE((trail[i] - trail[i - 1]).norm(), 1.0);
  EXPECT_LT((trail.back() - loop.state.position).norm(), 1.5);
  EXPECT_GT(trail.front().x(), 1.5);  // the start of the 35 m track is forgotten
}

}  // namespace
}  // namespace auv::control
