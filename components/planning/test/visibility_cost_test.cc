#include "auv/planning/visibility_cost.h"

#include <gtest/gtest.h>

#include <cmath>

#include "test_maps.h"

namespace auv::planning {
namespace {

VisibilityCostOptions costOptions() {
  VisibilityCostOptions options;
  options.expected_distance = 4.0;  // admissible interval [3, 5]
  options.admissible_range = 2.0;
  return options;
}

TEST(VisibilityCost, ZeroInsideTheAdmissibleIntervalEdgesIncluded) {
  const auto options = costOptions();
  EXPECT_DOUBLE_EQ(visibilityCost(3.0, options), 0.0);
  EXPECT_DOUBLE_EQ(visibilityCost(4.0, options), 0.0);
  EXPECT_DOUBLE_EQ(visibilityCost(5.0, options), 0.0);
}

TEST(VisibilityCost, FollowsEquationOneAroundTheEdges) {
  const auto options = costOptions();
  // Just outside the interval Eq. (1) jumps to (1 - d/d_e)·100 and (d/d_e - 1)·100.
  EXPECT_NEAR(visibilityCost(3.0 - 1e-9, options), 25.0, 1e-6);
  EXPECT_NEAR(visibilityCost(2.9, options), 27.5, 1e-9);
  EXPECT_NEAR(visibilityCost(5.0 + 1e-9, options), 25.0, 1e-6);
  EXPECT_NEAR(visibilityCost(5.1, options), 27.5, 1e-9);
  EXPECT_NEAR(visibilityCost(1.0, options), 75.0, 1e-9);
  EXPECT_NEAR(visibilityCost(6.0, options), 50.0, 1e-9);
}

TEST(VisibilityCost, BoundedToHundredAtContactAndFarAway) {
  const auto options = costOptions();
  EXPECT_DOUBLE_EQ(visibilityCost(0.0, options), 100.0);
  EXPECT_DOUBLE_EQ(visibilityCost(8.0, options), 100.0);
  EXPECT_DOUBLE_EQ(visibilityCost(50.0, options), 100.0);
}

TEST(VisibilityCost, RejectsBadParameters) {
  VisibilityCostOptions options;
  options.expected_distance = 0.0;
  EXPECT_THROW(options.check(), PlanningConfigError);
  options.expected_distance = 2.0;
  options.admissible_range = 4.0;
  EXPECT_THROW(options.check(), PlanningConfigError);
  options.admissible_range = -0.1;
  EXPECT_THROW(options.check(), PlanningConfigError);
}

/// Wall at x = 10 (cells x in [10, 10.5]) across y in [-10, 10]: d = distance to that plane.
class VisibilityObjectiveTest : public ::testing::Test {
 protected:
  void SetUp() override {
    testing::addOccupiedBox(*world_.tree, {10.0, -12.0, 0.0}, {10.5, 12.0, 10.0});
    world_.build();
    VisibilityObjectiveOptions options;
    options.cost = costOptions();
    options.visibility_weight = 1.0;
    objective_ = std::make_shared<VisibilityObjective>(world_.si, world_.field, options);
  }
  testing::FlatWorld world_;
  std::shared_ptr<VisibilityObjective> objective_;
};

TEST_F(VisibilityObjectiveTest, SegmentInsideTheAdmissibleBandCostsItsLength) {
  // Cell centres at x = 10.25: x = 6.25 is d = 4 from the wall, the middle of [3, 5].
  const auto from = world_.state(6.25, -3.0);
  const auto to = world_.state(6.25, 3.0);
  EXPECT_NEAR(objective_->motionCost(from.get(), to.get()).value(), 6.0, 1e-6);
}

TEST_F(VisibilityObjectiveTest, SegmentFarAwayCostsOnePlusWeightTimesLength) {
  const auto from = world_.state(0.5, -3.0);  // d = 9.75 > 2 d_e: Cost 100 (field clamped at 8)
  const auto to = world_.state(0.5, 3.0);
  EXPECT_NEAR(objective_->motionCost(from.get(), to.get()).value(), 12.0, 1e-6);
  EXPECT_NEAR(objective_->motionCostHeuristic(from.get(), to.get()).value(), 6.0, 1e-9);
}

TEST_F(VisibilityObjectiveTest, ZeroWeightIsPathLength) {
  VisibilityObjectiveOptions options;
  options.visibility_weight = 0.0;
  VisibilityObjective length_only(world_.si, world_.field, options);
  const auto from = world_.state(1.0, 1.0);
  const auto to = world_.state(4.0, 5.0);
  EXPECT_NEAR(length_only.motionCost(from.get(), to.get()).value(), 5.0, 1e-9);
}

TEST(VisibilityObjective3d, DistanceIsThreeDimensionalSoTheSeabedBelowIsSeen) {
  testing::FlatWorld world;
  world.three_d = true;
  // Only a seabed, top at 9 m: d of Eq. (1) is the vertical distance down to it.
  testing::addOccupiedBox(*world.tree, {0.0, -12.0, 9.0}, {22.0, 12.0, 10.0});
  world.build();
  VisibilityObjectiveOptions options;
  options.cost = costOptions();  // admissible d in [3, 5]
  VisibilityObjective objective(world.si, world.field, options);
  EXPECT_NEAR(objective.stateCost(world.state(10.0, 0.0, 5.0).get()).value(), 1.0, 1e-9);
  // d = 8 (1 m deep): (8 / 4 - 1)·100 = 100 -> density 2; d = 7: 75 -> 1.75; d = 2: 50 -> 1.5.
  EXPECT_NEAR(objective.stateCost(world.state(10.0, 0.0, 1.0).get()).value(), 2.0, 1e-9);
  EXPECT_NEAR(objective.stateCost(world.state(10.0, 0.0, 2.0).get()).value(), 1.75, 1e-9);
  EXPECT_NEAR(objective.stateCost(world.state(10.0, 0.0, 7.0).get()).value(), 1.5, 1e-9);
  // A level run at 5 m (d = 4) costs its length. A climb from 5 to 3 m leaves the admissible
  // interval at d = 5: 1 m at density 1, then 1 m from 1.25 to 1.5 (Eq. (1) jumps to 25 at
  // the edge), 2.375 in all; the trapezoid at 0.5 m steps gives 2.3125.
  EXPECT_NEAR(
      objective.motionCost(world.state(4.0, 0.0, 5.0).get(), world.state(16.0, 0.0, 5.0).get())
          .value(),
      12.0, 1e-6);
  const double climb =
      objective.motionCost(world.state(10.0, 0.0, 5.0).get(), world.state(10.0, 0.0, 3.0).get())
          .value();
  EXPECT_GT(climb, 2.25);
  EXPECT_LT(climb, 2.4);
  // The cost of a diagonal follows the 3-D length (its density is 1 all the way).
  EXPECT_NEAR(
      objective.motionCost(world.state(4.0, 0.0, 4.5).get(), world.state(7.0, 4.0, 5.5).get())
          .value(),
      std::sqrt(9.0 + 16.0 + 1.0), 1e-6);
}

TEST(VisibilityObjectiveNarrowPassage, HighCostNeverMakesThePassageInvalid) {
  testing::FlatWorld world;
  // Wall at x = 10 with a 4 m gap at |y| < 2: the gap centre is ~2 m from the wall cells.
  testing::addOccupiedBox(*world.tree, {10.0, -12.0, 0.0}, {10.5, -2.0, 10.0});
  testing::addOccupiedBox(*world.tree, {10.0, 2.0, 0.0}, {10.5, 12.0, 10.0});
  world.build();
  VisibilityObjectiveOptions options;
  options.cost.expected_distance = 6.0;  // the gap is far below d_e: high cost
  options.cost.admissible_range = 1.0;
  options.visibility_weight = 10.0;
  VisibilityObjective objective(world.si, world.field, options);
  const auto before = world.state(9.0, 0.0);
  const auto after = world.state(11.5, 0.0);
  EXPECT_TRUE(world.si->isValid(before.get()));
  EXPECT_TRUE(world.si->checkMotion(before.get(), after.get()));
  EXPECT_GT(objective.motionCost(before.get(), after.get()).value(), 2.5 * 5.0);
}

}  // namespace
}  // namespace auv::planning
