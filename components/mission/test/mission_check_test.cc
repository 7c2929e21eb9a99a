// Goals against what the vehicle knows: inside or too close to a known obstacle, deeper than
// the controller allows, and the plane of a fixed-depth query taken from the vehicle's depth.
#include <gtest/gtest.h>

#include <cmath>
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

/// A seabed: rock from 8 to 10 m deep over x, y in [0, 10]; open water seen (free cells)
/// from 2 to 4 m deep over x in [0, 5] only; a ledge (one layer at 5 m) over x, y in [6, 8].
octomap::OcTree seabed() {
  octomap::OcTree map(kResolution);
  for (double x = 0.25; x < 10; x += kResolution) {
    for (double y = 0.25; y < 10; y += kResolution) {
      for (double z = 8.25; z < 10; z += kResolution) map.updateNode(x, y, z, true);
      if (x < 5) {
        for (double z = 2.25; z < 4; z += kResolution) map.updateNode(x, y, z, false);
      }
    }
  }
  for (double x = 6.25; x < 8; x += kResolution) {
    for (double y = 6.25; y < 8; y += kResolution) map.updateNode(x, y, 5.25, true);
  }
  return map;
}

TEST(MissionCheckTest, GoalBelowTheSeabedIsRefused) {
  const octomap::OcTree map = seabed();
  // Under the rock with nothing seen between (the rock's inside is never seen): refused.
  const std::string why = refusal(queryTo({2.25, 2.25, 12.0}), &map, 2.0, limits(1.3));
  EXPECT_CONTAINS(why, "mission/start: query 'q' goal (2.25, 2.25, 12) is below the seabed");
  EXPECT_CONTAINS(why, "known rock at 10 m depth above it");
  EXPECT_CONTAINS(refusal(queryTo({7.25, 7.25, 7.0}), &map, 2.0, limits(0.5)), "below the seabed");
  // Above the seabed: accepted; beside it, over unknown ground: accepted.
  EXPECT_EQ(refusal(queryTo({2.25, 2.25, 5.0}), &map, 2.0, limits(1.3)), "");
  EXPECT_EQ(refusal(queryTo({12.25, 2.25, 12.0}), &map, 2.0, limits(1.3)), "");
  // Under an overhang with open water seen between the goal and the rock: not the seabed.
  octomap::OcTree arch(kResolution);
  arch.updateNode(2.25, 2.25, 1.25, true);
  for (double z = 1.75; z < 6; z += kResolution) arch.updateNode(2.25, 2.25, z, false);
  EXPECT_EQ(refusal(queryTo({2.25, 2.25, 5.25}), &arch, 2.0, limits(1.3)), "");
  // A fixed-depth plane (the paper's 2-D mode) is not checked against rock above it.
  MissionQuery plane = queryTo({7.25, 7.25, 0.0});
  plane.fixed_depth = true;
  plane.depth = 7.0;
  EXPECT_EQ(refusal(plane, &map, 2.0, limits(0.5)), "");
}

TEST(MissionCheckTest, GoalWithinMinAltitudeOfKnownSeabedIsRefused) {
  const octomap::OcTree map = seabed();
  MissionQuery low = queryTo({2.25, 2.25, 5.0});  // 3 m above the seabed's top (8 m)
  low.min_altitude = 2.0;                         // + 1.3 m clearance: 3.3 m needed
  const std::string why = refusal(low, &map, 2.0, limits(1.3));
  EXPECT_CONTAINS(why, "query 'q' goal (2.25, 2.25, 5) is 3 m above known seabed");
  EXPECT_CONTAINS(why, "min_altitude 2 m + the planner's 1.3 m clearance");
  low.min_altitude = 1.5;
  EXPECT_EQ(refusal(low, &map, 2.0, limits(1.3)), "");
  // Over unknown ground nothing is known below: accepted.
  MissionQuery unknown = queryTo({12.25, 2.25, 5.0});
  unknown.min_altitude = 2.0;
  EXPECT_EQ(refusal(unknown, &map, 2.0, limits(1.3)), "");
  EXPECT_DOUBLE_EQ(altitudeOverSeabed(map, {2.25, 2.25, 5.0}, 10.0), 3.0);
  EXPECT_TRUE(std::isinf(altitudeOverSeabed(map, {2.25, 2.25, 5.0}, 2.5)));
}

TEST(MissionCheckTest, BandDeeperThanTheVehiclesMaxDepthIsRefused) {
  MissionQuery deep = queryTo({5, 5, 10});
  deep.min_depth = 2.0;
  deep.max_depth = 25.0;
  EXPECT_CONTAINS(refusal(deep, nullptr, 2.0, limits(1.3, 20.0)),
                  "mission/start: query 'q' max_depth: the band reaches 25 m, deeper than the "
                  "vehicle's max_depth 20 m");
  deep.max_depth = 20.0;
  EXPECT_EQ(refusal(deep, nullptr, 2.0, limits(1.3, 20.0)), "");
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
