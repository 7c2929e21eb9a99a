#include "auv/planning/map_validity.h"

#include <gtest/gtest.h>

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

TEST(MapValidity, RejectsBadOptions) {
  PlanningSpaceOptions space;
  space.fixed_depth = 100.0;
  EXPECT_THROW(space.check(), PlanningConfigError);
  ClearanceOptions clearance;
  clearance.hull_radius = -1.0;
  EXPECT_THROW(clearance.check(), PlanningConfigError);
}

}  // namespace
}  // namespace auv::planning
