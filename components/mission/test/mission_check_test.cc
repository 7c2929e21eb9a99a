// Goals against what the vehicle knows: inside or too close to a known obstacle, deeper than
// the controller allows, and the plane of a fixed-depth query taken from the vehicle's depth.
#include <gtest/gtest.h>

#include <string>

#include "auv/mission/mission_check.h"

namespace auv::mission {
namespace {

constexpr double kResolution = 0.5;

#define EXPECT_CONTAINS(text, part) \
  EXPECT_NE(std::string(text).find(part), std::string::npos) << "'" << (text) << "'"

/// One occupied leaf: the cell [10, 10.5] x [0, 0.5] x [5, 5.5] (centre 10.25, 0.25, 5.25).
octomap::OcTree oneCell() {
  octomap::OcTree map(kResolution);
  map.updateNode(octomap::point3d(10.25f, 0.25f, 5.25f), true);
  // Known free space farther away is no obstacle.
  map.updateNode(octomap::point3d(13.25f, 0.25f, 5.25f), false);
  return map;
}

/// Explicit limits: the tests do not depend on the defaults.
MissionLimits limits(double goal_clearance = 1.3, double max_depth = 50.0) {
  MissionLimits l;
  l.goal_clearance = goal_clearance;
  l.max_depth = max_depth;
  return l;
}

MissionQuery queryTo(const Eigen::Vector3d& goal) {
  MissionQuery query;
  query.name = "q";
  query.goal = goal;
  query.bounds_min = {-50, -50, 0};
  query.bounds_max = {50, 50, 40};
  return query;
}

/// The reason checkAgainstVehicle refuses `query`, or "" when it accepts it.
std::string refusal(const MissionQuery& query, const octomap::OcTree* map, double vehicle_depth,
                    const MissionLimits& limits) {
  try {
    checkAgainstVehicle({query}, map, vehicle_depth, limits, "mission/start");
  } catch (const MissionError& error) {
    return error.what();
  }
  return "";
}

TEST(MissionCheckTest, GoalInsideAnOccupiedCellIsRefused) {
  const octomap::OcTree map = oneCell();
  // At the centre and off-centre inside the cell: both inside.
  for (const Eigen::Vector3d& goal :
       {Eigen::Vector3d(10.25, 0.25, 5.25), Eigen::Vector3d(10.45, 0.05, 5.4)}) {
    const std::string why = refusal(queryTo(goal), &map, 2.0, limits(1.3));
    EXPECT_CONTAINS(why, "mission/start: query 'q' goal");
    EXPECT_CONTAINS(why, "inside a known obstacle");
    EXPECT_CONTAINS(why, "(0 m from occupied space; the planner keeps 1.3 m)");
  }
}

TEST(MissionCheckTest, GoalWithinTheClearanceIsRefusedWithTheDistance) {
  const octomap::OcTree map = oneCell();
  // 0.5 m north of the cell's face (the distance counts to the cell, not its centre).
  const std::string why = refusal(queryTo({11.0, 0.25, 5.25}), &map, 2.0, limits(1.3));
  EXPECT_CONTAINS(why, "(11, 0.25, 5.25)");
  EXPECT_CONTAINS(why, "too close to a known obstacle");
  EXPECT_CONTAINS(why, "0.5 m from occupied space");
  EXPECT_CONTAINS(why, "keeps 1.3 m");
  // 1.2 m below the cell: still too close.
  EXPECT_CONTAINS(refusal(queryTo({10.25, 0.25, 6.7}), &map, 2.0, limits(1.3)), "1.2 m");
}

TEST(MissionCheckTest, GoalBeyondTheClearanceIsAccepted) {
  const octomap::OcTree map = oneCell();
  EXPECT_EQ(refusal(queryTo({12.0, 0.25, 5.25}), &map, 2.0, limits(1.3)), "");   // 1.5 m
  EXPECT_EQ(refusal(queryTo({13.25, 0.25, 5.25}), &map, 2.0, limits(1.3)), "");  // a free cell
  // A smaller clearance accepts what the larger one refused.
  EXPECT_EQ(refusal(queryTo({11.0, 0.25, 5.25}), &map, 2.0, limits(0.4)), "");
  // No map yet: nothing to refuse for.
  EXPECT_EQ(refusal(queryTo({10.25, 0.25, 5.25}), nullptr, 2.0, limits(1.3)), "");
}

TEST(MissionCheckTest, GoalInsideACoarseLeafIsInside) {
  // Eight occupied cells that OctoMap prunes into one 1 m leaf centred at (20.5, 0.5, 5.5).
  octomap::OcTree map(kResolution);
  for (double x : {20.25, 20.75}) {
    for (double y : {0.25, 0.75}) {
      for (double z : {5.25, 5.75}) map.updateNode(octomap::point3d(x, y, z), true);
    }
  }
  map.prune();
  ASSERT_EQ(map.getNumLeafNodes(), 1u);
  // Near a corner of the coarse leaf: 0.69 m from its centre but inside it.
  EXPECT_CONTAINS(refusal(queryTo({20.1, 0.1, 5.1}), &map, 2.0, limits(1.3)),
                  "inside a known obstacle");
  EXPECT_NEAR(distanceToOccupied(map, {22.0, 0.5, 5.5}, 2.0), 1.0, 1e-6);
  EXPECT_GT(distanceToOccupied(map, {30.0, 0.5, 5.5}, 2.0), 2.0);  // none within the radius
}

TEST(MissionCheckTest, GoalDeeperThanMaxDepthIsUnreachable) {
  const std::string why = refusal(queryTo({5, 5, 25}), nullptr, 2.0, limits(1.3, 20.0));
  EXPECT_CONTAINS(why, "query 'q' goal (5, 5, 25)");
  EXPECT_CONTAINS(why, "max_depth 20 m");
  EXPECT_CONTAINS(why, "unreachable depth");
  EXPECT_EQ(refusal(queryTo({5, 5, 20}), nullptr, 2.0, limits(1.3, 20.0)), "");
}

TEST(MissionCheckTest, FixedDepthPlaneComesFromTheVehicleWhenUnset) {
  const MissionLimits shallow = limits(1.3, 20.0);
  MissionQuery plane = queryTo({5, 5, 3});  // goal z is not the plane's depth
  plane.fixed_depth = true;
  // Unset depth: the vehicle's.
  EXPECT_CONTAINS(refusal(plane, nullptr, 30.0, shallow), "(5, 5, 30)");
  EXPECT_CONTAINS(refusal(plane, nullptr, 30.0, shallow), "unreachable depth");
  EXPECT_EQ(refusal(plane, nullptr, 10.0, shallow), "");
  // Set depth: its own, whatever the vehicle's.
  plane.depth = 12.0;
  EXPECT_EQ(refusal(plane, nullptr, 30.0, shallow), "");
  plane.depth = 21.0;
  EXPECT_CONTAINS(refusal(plane, nullptr, 2.0, shallow), "(5, 5, 21)");

  // The obstacle test uses the plane too: a cell at 5.25 m blocks the goal only on that plane.
  const octomap::OcTree map = oneCell();
  MissionQuery over_cell = queryTo({10.25, 0.25, 15});
  over_cell.fixed_depth = true;
  EXPECT_CONTAINS(refusal(over_cell, &map, 5.25, limits(1.3)), "inside a known obstacle");
  EXPECT_EQ(refusal(over_cell, &map, 15.0, limits(1.3)), "");
}

TEST(MissionCheckTest, EveryQueryIsCheckedAndTheRefusedOneNamed) {
  MissionQuery good = queryTo({1, 1, 5});
  good.name = "good";
  MissionQuery deep = queryTo({1, 1, 35});
  deep.name = "deep";
  try {
    checkAgainstVehicle({good, deep}, nullptr, 2.0, limits(1.3, 20.0), "plan.yaml");
    FAIL() << "the second query was not checked";
  } catch (const MissionError& error) {
    EXPECT_CONTAINS(error.what(), "plan.yaml: query 'deep'");
  }
}

}  // namespace
}  // namespace auv::mission
