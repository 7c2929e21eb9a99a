#include "auv/planning/map_validity.h"

#include <gtest/gtest.h>

#include <cmath>

#include "test_maps.h"

namespace auv::planning {
namespace {

TEST(MapValidity, UnknownSpaceIsFreeAndClearanceIsEnforced) {
  testing::FlatWorld world;
  testing::addOccupiedBox(*world.tree, {10.0, -1.0, 0.0}, {10.5, 1.0, 10.0});
  world.build();
  EXPECT_TRUE(world.si->isValid(world.state(5.0, 0.0).get()));    // unknown, far
  EXPECT_TRUE(world.si->isValid(world.state(8.75, 0.0).get()));   // 1.5 m from cell centres
  EXPECT_FALSE(world.si->isValid(world.state(9.75, 0.0).get()));  // 0.5 m < 1 m clearance
  EXPECT_FALSE(world.si->isValid(world.state(10.25, 0.0).get()));
}

TEST(MapValidity, LongMotionsDoNotStepOverAThinWall) {
  testing::FlatWorld world;
  testing::addOccupiedBox(*world.tree, {10.0, -10.0, 0.0}, {10.5, 10.0, 10.0});
  world.build();
  EXPECT_FALSE(world.si->checkMotion(world.state(1.0, 0.0).get(), world.state(19.0, 3.0).get()));
  EXPECT_TRUE(world.si->checkMotion(world.state(1.0, -9.0).get(), world.state(8.0, 9.0).get()));
  // Also OMPL's own discretisation (used by code that bypasses the motion validator).
  EXPECT_LE(world.si->getStateValidityCheckingResolution() *
                world.si->getStateSpace()->getMaximumExtent(),
            0.5 * testing::kResolution + 1e-9);
}

TEST(MapValidity, AStartInsideTheMarginMayOnlyBeLeftByMovingAway) {
  testing::FlatWorld world;  // clearance 1 m
  testing::addOccupiedBox(*world.tree, {10.0, -10.0, 0.0}, {10.5, 10.0, 10.0});
  world.build();
  const auto inside = world.state(9.5, 0.0);  // 0.75 m from the wall's cell centres
  ASSERT_FALSE(world.si->isValid(inside.get()));
  // Straight away from the wall, into valid space: allowed.
  EXPECT_TRUE(world.si->checkMotion(inside.get(), world.state(6.0, 0.0).get()));
  // Along the wall, never getting valid: refused; towards it: refused.
  EXPECT_FALSE(world.si->checkMotion(inside.get(), world.state(9.5, 5.0).get()));
  EXPECT_FALSE(world.si->checkMotion(inside.get(), world.state(9.75, 0.0).get()));
  // Away, then back into the margin: the escape ends once valid, so refused.
  const auto valid = world.state(7.0, 0.0);
  ASSERT_TRUE(world.si->isValid(valid.get()));
  EXPECT_FALSE(world.si->checkMotion(valid.get(), world.state(9.5, 1.0).get()));
}

TEST(MapValidity, FixedDepthKeepsSampledStatesAtThatDepth) {
  testing::FlatWorld world;
  world.build();
  auto sampler = world.si->allocStateSampler();
  ompl::base::ScopedState<> state(world.si);
  for (int i = 0; i < 100; ++i) {
    sampler->sampleUniform(state.get());
    EXPECT_DOUBLE_EQ(state[2], testing::FlatWorld::kDepth);
    EXPECT_TRUE(world.si->satisfiesBounds(state.get()));
  }
}

TEST(MapValidity, ClearanceIsASphereSoRockAboveTheHullCounts) {
  testing::FlatWorld world;  // clearance 1 m
  world.three_d = true;
  world.clearance.min_altitude = 2.0;
  // An overhang: rock between 2 and 3 m deep (NED), open water under it, nothing below.
  testing::addOccupiedBox(*world.tree, {8.0, -2.0, 2.0}, {12.0, 2.0, 3.0});
  world.build();
  EXPECT_FALSE(world.si->isValid(world.state(10.0, 0.0, 3.75).get()));  // 0.75 m under it
  EXPECT_TRUE(world.si->isValid(world.state(10.0, 0.0, 4.25).get()));   // 1.25 m under it
  // Beside the rock at the same depth: the sphere reaches sideways as well.
  EXPECT_FALSE(world.si->isValid(world.state(12.75, 0.0, 2.5).get()));
  EXPECT_TRUE(world.si->isValid(world.state(13.25, 0.0, 2.5).get()));
  // Rising into the rock from below is refused; passing under it with the clearance is not.
  EXPECT_FALSE(
      world.si->checkMotion(world.state(10.0, 0.0, 6.0).get(), world.state(10.0, 0.0, 3.5).get()));
  EXPECT_TRUE(
      world.si->checkMotion(world.state(5.0, 0.0, 4.5).get(), world.state(15.0, 0.0, 4.5).get()));
}

TEST(MapValidity, MinAltitudeKeepsStatesAboveKnownSeabedOnly) {
  // Seabed (top at 8 m) known under x >= 10 only; elsewhere below is unknown, hence free.
  const auto seabed = [](testing::FlatWorld& world) {
    testing::addOccupiedBox(*world.tree, {10.0, -10.0, 8.0}, {20.0, 10.0, 10.0});
    world.build();
  };
  testing::FlatWorld sphere_only;  // clearance 1 m, min_altitude 0
  sphere_only.three_d = true;
  seabed(sphere_only);
  testing::FlatWorld world;
  world.three_d = true;
  world.clearance.min_altitude = 1.5;  // states keep 1.5 + 1 m of water down to the seabed
  seabed(world);
  for (const testing::FlatWorld* w : {&sphere_only, &world}) {
    EXPECT_TRUE(w->si->isValid(w->state(15.0, 0.0, 5.25).get()));   // 2.75 m over it
    EXPECT_FALSE(w->si->isValid(w->state(15.0, 0.0, 7.25).get()));  // 0.75 m: the sphere
    EXPECT_TRUE(w->si->isValid(w->state(5.0, 0.0, 9.5).get()));     // over unknown space
  }
  // 2.25 m over the seabed: clear of the sphere, not of min_altitude + clearance (2.5 m).
  EXPECT_TRUE(sphere_only.si->isValid(sphere_only.state(15.0, 0.0, 5.75).get()));
  const auto low = world.state(15.0, 0.0, 5.75);
  EXPECT_FALSE(world.si->isValid(low.get()));
  EXPECT_NEAR(world.si->getStateValidityChecker()->clearance(low.get()), -0.25, 1e-9);
  EXPECT_NEAR(world.field->altitude({15.0, 0.0, 5.75}, 10.0), 2.25, 1e-9);
  EXPECT_TRUE(std::isinf(world.field->altitude({5.0, 0.0, 5.75}, 10.0)));  // nothing known
  EXPECT_TRUE(std::isinf(world.field->altitude({15.0, 0.0, 5.75}, 2.0)));  // beyond reach
  // Motions are stepped: a level run from unknown ground over the seabed too low is refused.
  EXPECT_FALSE(
      world.si->checkMotion(world.state(5.0, 0.0, 5.75).get(), world.state(18.0, 0.0, 5.75).get()));
  EXPECT_TRUE(
      world.si->checkMotion(world.state(5.0, 0.0, 5.25).get(), world.state(18.0, 0.0, 5.25).get()));
  // A state that finds itself too low may climb away, not run along the seabed.
  EXPECT_TRUE(world.si->checkMotion(low.get(), world.state(15.0, 0.0, 4.0).get()));
  EXPECT_FALSE(world.si->checkMotion(low.get(), world.state(19.0, 0.0, 5.75).get()));
}

TEST(MapValidity, MotionsNoSteeperThanTheClimbAngle) {
  testing::FlatWorld world;  // open water, default max_climb_angle 20 deg
  world.three_d = true;
  world.build();
  const auto from = world.state(5.0, 0.0, 5.0);
  // Rising 2 m over 10 m (11 deg): valid; over 4 m (27 deg) or straight up: not. Dives are
  // not limited (the DVL and MIN_ALTITUDE watch below; nothing looks up but the fan).
  EXPECT_TRUE(world.si->checkMotion(from.get(), world.state(15.0, 0.0, 3.0).get()));
  EXPECT_FALSE(world.si->checkMotion(from.get(), world.state(9.0, 0.0, 3.0).get()));
  EXPECT_FALSE(world.si->checkMotion(from.get(), world.state(5.0, 0.0, 3.0).get()));
  EXPECT_TRUE(world.si->checkMotion(from.get(), world.state(9.0, 0.0, 7.0).get()));
  EXPECT_TRUE(world.si->checkMotion(from.get(), world.state(5.0, 0.0, 7.0).get()));
  std::pair<ompl::base::State*, double> last_valid(nullptr, 1.0);
  EXPECT_FALSE(world.si->checkMotion(from.get(), world.state(5.0, 0.0, 3.0).get(), last_valid));
  EXPECT_EQ(last_valid.second, 0.0);  // none of it is valid
  // Steering: a state too high above `from` is lowered onto the limit, a lower one kept.
  const auto* validator =
      dynamic_cast<const MapMotionValidator*>(world.si->getMotionValidator().get());
  ASSERT_NE(validator, nullptr);
  auto steered = world.state(9.0, 3.0, 1.0);  // 5 m horizontally, 4 m up
  validator->limitClimb(from.get(), steered.get());
  EXPECT_NEAR(steered[2], 5.0 - std::tan(20.0 * M_PI / 180.0) * 5.0, 1e-9);
  EXPECT_TRUE(world.si->checkMotion(from.get(), steered.get()));
  auto deeper = world.state(9.0, 3.0, 9.0);
  validator->limitClimb(from.get(), deeper.get());
  EXPECT_DOUBLE_EQ(deeper[2], 9.0);
  // 90 deg lifts the limit.
  testing::FlatWorld free_climb;
  free_climb.three_d = true;
  free_climb.clearance.max_climb_angle = 90.0;
  free_climb.build();
  EXPECT_TRUE(free_climb.si->checkMotion(free_climb.state(5.0, 0.0, 5.0).get(),
                                         free_climb.state(5.0, 0.0, 3.0).get()));
}

TEST(MapValidity, RejectsBadOptions) {
  PlanningSpaceOptions space;
  space.fixed_depth = 100.0;
  EXPECT_THROW(space.check(), PlanningConfigError);
  ClearanceOptions clearance;
  clearance.hull_radius = -1.0;
  EXPECT_THROW(clearance.check(), PlanningConfigError);
  clearance = ClearanceOptions();
  clearance.min_altitude = -0.5;
  EXPECT_THROW(clearance.check(), PlanningConfigError);
  for (double angle : {0.0, 91.0}) {
    clearance = ClearanceOptions();
    clearance.max_climb_angle = angle;
    EXPECT_THROW(clearance.check(), PlanningConfigError) << angle;
  }
}

}  // namespace
}  // namespace auv::planning
