// 3-D queries of the planning session (issue 19): the depth band bounds every tree node and
// waypoint, a start outside the band is brought into it, bad bands and goals outside the band
// are refused, min_altitude keeps the tree above known seabed, the 2-D modes ignore the band,
// and a boulder is passed over when the band allows and around when it does not. The slices
// grow the tree for real (50 ms of wall time each).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <octomap/OcTree.h>

#include "auv/planning/planning_session.h"
#include "auv/planning/visibility_cost.h"
#include "test_maps.h"

namespace auv::planning {
namespace {

using testing::addOccupiedBox;
using testing::kResolution;

constexpr double kClearance = 1.0;
const Eigen::Vector3d kBoundsMin(0.0, -10.0, 0.0);
const Eigen::Vector3d kBoundsMax(20.0, 10.0, 10.0);

SessionOptions defaults() {
  SessionOptions o;
  o.map_resolution = kResolution;
  o.clearance.hull_radius = 0.6;
  o.clearance.safety_margin = kClearance - 0.6;
  o.range = 3.0;
  o.iteration_budget = 0.05;
  o.max_distance = 8.0;
  o.max_tree_size = 4000;
  return o;
}

PlanningQuery query3d(const Eigen::Vector3d& start, const Eigen::Vector3d& goal, double min_depth,
                      double max_depth) {
  PlanningQuery q;
  q.query_id = 1;
  q.start = start;
  q.goal = goal;
  q.goal_tolerance = 1.0;
  q.objective = PlanningObjective::PATH_LENGTH;
  q.bounds_min = kBoundsMin;
  q.bounds_max = kBoundsMax;
  q.min_depth = min_depth;
  q.max_depth = max_depth;
  return q;
}

class Session3dTest : public ::testing::Test {
 protected:
  explicit Session3dTest(const SessionOptions& options = defaults()) : session(options) {}

  bool start(const PlanningQuery& query) {
    query_ = query;
    const bool started = session.startQuery(query, map, query.start, 100.0);
    outbox = session.takeOutbox();
    return started;
  }
  /// Slices until the tree has a solution (false after `limit`), then `extra` more.
  bool solve(int extra = 0, int limit = 200) {
    double t = 100.0;
    for (int i = 0; i < limit && !session.planner()->hasSolution(); ++i) {
      session.planSlice(query_.start, t += 0.1);
    }
    for (int j = 0; j < extra; ++j) session.planSlice(query_.start, t += 0.1);
    return session.planner()->hasSolution();
  }
  /// The refusal text of a query that did not start.
  std::string refusal() const {
    for (const auto& m : outbox.messages) {
      if (const auto* c = std::get_if<WaypointCancel>(&m)) return c->text;
    }
    return "";
  }
  /// The best path; every edge is checked again on the session's space.
  std::vector<Eigen::Vector3d> checkedPath() const {
    const auto& si = session.planner()->spaceInformation();
    const auto states = session.planner()->bestPath();
    std::vector<Eigen::Vector3d> path;
    for (std::size_t i = 0; i < states.size(); ++i) {
      if (i > 0) {
        EXPECT_TRUE(si->checkMotion(states[i - 1], states[i])) << "edge " << i;
      }
      path.push_back(statePosition(states[i]));
    }
    return path;
  }

  octomap::OcTree map{kResolution};
  PlanningSession session;
  PlanningQuery query_;
  PlanningSession::Outbox outbox;
};

TEST_F(Session3dTest, EveryNodeAndWaypointStaysInTheBand) {
  ASSERT_TRUE(start(query3d({2.0, 0.0, 4.5}, {18.0, 0.0, 5.0}, 3.0, 6.0)));
  ASSERT_TRUE(solve(10));
  const TreeSnapshot tree = session.tree();
  double shallowest = 10.0, deepest = 0.0;
  for (const Eigen::Vector3d& node : tree.nodes) {
    shallowest = std::min(shallowest, node.z());
    deepest = std::max(deepest, node.z());
  }
  EXPECT_GE(shallowest, 3.0);
  EXPECT_LE(deepest, 6.0);
  EXPECT_GT(deepest - shallowest, 1.5) << "depth is sampled: the tree is not a plane";
  // Waypoint by waypoint to the goal.
  session.onWaypointRequest({1, 0}, 200.0);
  std::vector<PlannedWaypoint> waypoints;
  for (int i = 0; i < 40; ++i) {
    for (const auto& m : session.takeOutbox().messages) {
      if (const auto* w = std::get_if<PlannedWaypoint>(&m)) waypoints.push_back(*w);
    }
    if (!waypoints.empty() && waypoints.back().is_final) break;
    if (!waypoints.empty()) session.onWaypointRequest({1, waypoints.back().waypoint_id}, 200.0 + i);
    session.planSlice(waypoints.empty() ? query_.start : waypoints.back().position, 200.0 + i);
    session.finishSlice(200.0 + i);
  }
  ASSERT_FALSE(waypoints.empty());
  EXPECT_TRUE(waypoints.back().is_final);
  for (const PlannedWaypoint& w : waypoints) {
    EXPECT_GE(w.position.z(), 3.0);
    EXPECT_LE(w.position.z(), 6.0);
  }
}

TEST_F(Session3dTest, AStartOutsideTheBandIsRootedAtItsNearestDepthInside) {
  ASSERT_TRUE(start(query3d({2.0, 0.0, 1.2}, {18.0, 0.0, 5.0}, 3.0, 6.0)));
  const Eigen::Vector3d root = statePosition(session.planner()->rootState());
  EXPECT_DOUBLE_EQ(root.z(), 3.0);
  EXPECT_DOUBLE_EQ(root.x(), 2.0);
  ASSERT_TRUE(solve());
  for (const Eigen::Vector3d& node : session.tree().nodes) EXPECT_GE(node.z(), 3.0);
}

TEST_F(Session3dTest, BadBandsAndGoalsOutsideTheBandAreRefused) {
  EXPECT_FALSE(start(query3d({2.0, 0.0, 4.0}, {18.0, 0.0, 5.0}, 6.0, 3.0)));
  EXPECT_NE(refusal().find("min_depth 6 m must be above max_depth 3 m"), std::string::npos)
      << refusal();
  EXPECT_FALSE(session.hasQuery());
  EXPECT_FALSE(start(query3d({2.0, 0.0, 4.0}, {18.0, 0.0, 5.0}, 12.0, 15.0)));
  EXPECT_NE(refusal().find("outside the bounds' z-range"), std::string::npos) << refusal();
  EXPECT_FALSE(start(query3d({2.0, 0.0, 4.0}, {18.0, 0.0, 8.0}, 3.0, 6.0)));
  EXPECT_NE(refusal().find("goal depth 8 m is outside the depth band [3 m, 6 m]"),
            std::string::npos)
      << refusal();
  PlanningQuery negative = query3d({2.0, 0.0, 4.0}, {18.0, 0.0, 5.0}, 3.0, 6.0);
  negative.min_altitude = -1.0;
  EXPECT_FALSE(start(negative));
  EXPECT_NE(refusal().find("min_altitude"), std::string::npos) << refusal();
  // A band reaching past the bounds is cut to them.
  ASSERT_TRUE(start(query3d({2.0, 0.0, 4.0}, {18.0, 0.0, 9.0}, 3.0, 40.0)));
  ASSERT_TRUE(solve());
  for (const Eigen::Vector3d& node : session.tree().nodes) EXPECT_LE(node.z(), 10.0);
}

TEST_F(Session3dTest, MinAltitudeKeepsTheTreeAboveTheKnownSeabed) {
  addOccupiedBox(map, {0.0, -10.0, 8.0}, {20.0, 10.0, 10.0});  // seabed, top at 8 m
  PlanningQuery q = query3d({2.0, 0.0, 4.0}, {18.0, 0.0, 4.0}, 1.0, 9.0);
  q.min_altitude = 2.0;  // with the 1 m clearance: nothing deeper than 5 m
  ASSERT_TRUE(start(q));
  ASSERT_TRUE(solve(10));
  double deepest = 0.0;
  for (const Eigen::Vector3d& node : session.tree().nodes) deepest = std::max(deepest, node.z());
  EXPECT_LE(deepest, 5.0);
  EXPECT_GT(deepest, 4.5) << "the tree reaches down to the limit";
  for (const Eigen::Vector3d& p : checkedPath()) EXPECT_LE(p.z(), 5.0);
}

TEST_F(Session3dTest, ASeabedMappedUnderTheTreeRemovesTheNodesTooLowOverIt) {
  PlanningQuery q = query3d({2.0, 0.0, 4.0}, {18.0, 0.0, 4.0}, 1.0, 9.0);
  q.min_altitude = 2.0;  // with the 1 m clearance: 3 m of water over known seabed
  ASSERT_TRUE(start(q));
  ASSERT_TRUE(solve(10));
  const auto tooLow = [](const Eigen::Vector3d& p) { return p.x() > 10.5 && p.z() > 5.0; };
  const auto countTooLow = [&] {
    const auto nodes = session.tree().nodes;
    return std::count_if(nodes.begin(), nodes.end(), tooLow);
  };
  ASSERT_GT(countTooLow(), 0);
  // The seabed (top at 8 m) under x >= 10, as the mapping reports it: the changed box only.
  const Eigen::Vector3d changed_min(10.0, -10.0, 8.0), changed_max(20.0, 10.0, 10.0);
  addOccupiedBox(map, changed_min, changed_max);
  session.onMapIncrement(changed_min, changed_max, 1);
  session.planSlice(query_.start, 200.0);
  EXPECT_EQ(countTooLow(), 0) << "nodes within min_altitude + clearance of the seabed kept";
  EXPECT_GT(session.tree().nodes.size(), 10u);
}

TEST_F(Session3dTest, FixedDepthQueriesIgnoreTheBand) {
  PlanningQuery q = query3d({2.0, 0.0, 7.0}, {18.0, 0.0, 7.0}, 3.0, 6.0);
  q.fixed_depth = 7.0;  // the paper's 2-D mode: the plane, band or not
  ASSERT_TRUE(start(q));
  ASSERT_TRUE(solve());
  for (const Eigen::Vector3d& node : session.tree().nodes) EXPECT_DOUBLE_EQ(node.z(), 7.0);
}

class Session3dForced2dTest : public Session3dTest {
 protected:
  static SessionOptions forced() {
    SessionOptions o = defaults();
    o.fixed_depth = true;
    return o;
  }
  Session3dForced2dTest() : Session3dTest(forced()) {}
};

TEST_F(Session3dForced2dTest, ThePlannersFixedDepthOptionPlansAtTheStartDepth) {
  ASSERT_TRUE(start(query3d({2.0, 0.0, 4.5}, {18.0, 0.0, 5.5}, 3.0, 6.0)));
  ASSERT_TRUE(solve());
  for (const Eigen::Vector3d& node : session.tree().nodes) EXPECT_DOUBLE_EQ(node.z(), 4.5);
}

// A boulder in the way, its top at 5 m (rock from 5 to 10 m deep), 8 m wide across y: over
// its top the vehicle needs 4 m or shallower (1 m clearance).
void addBoulder(octomap::OcTree& map, double half_width) {
  addOccupiedBox(map, {8.0, -half_width, 5.0}, {12.0, half_width, 10.0});
}

TEST_F(Session3dTest, ARidgeIsPassedOverItsTopWhenTheBandAllows) {
  addBoulder(map, 10.0);  // across the whole bounds: no way around
  ASSERT_TRUE(start(query3d({2.0, 0.0, 7.0}, {18.0, 0.0, 7.0}, 1.0, 9.0)));
  ASSERT_TRUE(solve());
  double over_top = 10.0;
  for (const Eigen::Vector3d& p : checkedPath()) {
    if (p.x() > 8.0 && p.x() < 12.0) over_top = std::min(over_top, p.z());
  }
  EXPECT_LE(over_top, 4.0);
  // The same ridge with a band below its top: no way over, and none around (40 slices, 2 s,
  // grow a full tree).
  ASSERT_TRUE(start(query3d({2.0, 0.0, 7.0}, {18.0, 0.0, 7.0}, 5.5, 9.0)));
  EXPECT_FALSE(solve(0, 40));
  EXPECT_GT(session.tree().nodes.size(), 100u);
}

TEST_F(Session3dTest, ABoulderIsPassedAroundWhenTheBandKeepsTheVehicleBelowItsTop) {
  addBoulder(map, 4.0);  // y in [-4, 4]
  ASSERT_TRUE(start(query3d({2.0, 0.0, 7.0}, {18.0, 0.0, 7.0}, 5.5, 9.0)));
  ASSERT_TRUE(solve());
  double widest = 0.0;
  for (const Eigen::Vector3d& p : checkedPath()) {
    EXPECT_GE(p.z(), 5.5);
    widest = std::max(widest, std::abs(p.y()));
  }
  EXPECT_GE(widest, 5.0) << "the path goes beside the boulder";
  // With room above it, a path exists too, and any path the planner keeps is valid.
  ASSERT_TRUE(start(query3d({2.0, 0.0, 7.0}, {18.0, 0.0, 7.0}, 1.0, 9.0)));
  ASSERT_TRUE(solve());
  EXPECT_GE(checkedPath().size(), 2u);
}

TEST_F(Session3dTest, AGoalHighAboveTheStartIsReachedByAClimbNoSteeperThanTheLimit) {
  // 5 m up over 8 m (32 deg) in open water: steeper than max_climb_angle (20 deg), so the way
  // up is a longer, shallower one; the tree steers its climbs to the limit instead of giving
  // up on every sample above a node (the nearest node to the goal is often right below it).
  ASSERT_TRUE(start(query3d({4.0, 0.0, 8.5}, {12.0, 0.0, 3.0}, 1.0, 9.0)));
  ASSERT_TRUE(solve(0, 100));
  const std::vector<Eigen::Vector3d> path = checkedPath();
  const double max_slope = std::tan(ClearanceOptions().max_climb_angle * M_PI / 180.0);
  for (std::size_t i = 1; i < path.size(); ++i) {
    const Eigen::Vector3d step = path[i] - path[i - 1];
    EXPECT_LE(-step.z(), max_slope * step.head<2>().norm() + 1e-6) << "edge " << i;
  }
}

}  // namespace
}  // namespace auv::planning
