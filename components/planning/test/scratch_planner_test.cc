// The from-scratch baselines (replanning: scratch, OMPL's RRTstar; restart, OnlineRRTstar
// without the reuse) behind the session's query and waypoint protocol: it answers waypoint requests
// up to the goal, starts a new tree (sharing no node with the old one) on every map change and
// every waypoint handed out, drops the plan it follows once a wall blocks it and goes round,
// cancels a blocked root like the repair planner, and the option is validated. The slices grow the
// trees for real (50 ms of wall time each).
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include <ompl/base/objectives/PathLengthOptimizationObjective.h>

#include "auv/planning/planning_session.h"
#include "auv/planning/scratch_planner.h"
#include "test_maps.h"

namespace auv::planning {
namespace {

using testing::addOccupiedBox;
using testing::kResolution;

constexpr double kDepth = 5.0;
constexpr double kHullRadius = 0.6;
constexpr double kRange = 3.0;
const Eigen::Vector3d kStart(2.0, 0.0, kDepth);
const Eigen::Vector3d kGoal(18.0, 0.0, kDepth);

SessionOptions scratchOptions(const std::string& replanning = "scratch") {
  SessionOptions o;
  o.replanning = replanning;
  o.map_resolution = kResolution;
  o.clearance.hull_radius = kHullRadius;
  o.clearance.safety_margin = 0.4;
  o.range = kRange;
  o.iteration_budget = 0.05;
  o.max_distance = 8.0;
  o.max_tree_size = 3000;
  return o;
}

PlanningQuery makeQuery(uint64_t id) {
  PlanningQuery q;
  q.query_id = id;
  q.start = kStart;
  q.goal = kGoal;
  q.goal_tolerance = 1.0;
  q.objective = PlanningObjective::VISIBILITY_COST;
  q.expected_distance = 3.0;
  q.admissible_range = 1.0;
  q.bounds_min = {0.0, -10.0, 4.0};
  q.bounds_max = {20.0, 10.0, 6.0};
  q.fixed_depth = kDepth;
  return q;
}

/// The segment keeps the hull out of `box` (sampled every 5 cm).
bool clearOf(const Eigen::AlignedBox3d& box, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const int steps = std::max(1, static_cast<int>((b - a).norm() / 0.05));
  for (int i = 0; i <= steps; ++i) {
    if (box.exteriorDistance(a + (b - a) * (static_cast<double>(i) / steps)) < kHullRadius) {
      return false;
    }
  }
  return true;
}

class ScratchSessionTest : public ::testing::TestWithParam<std::string> {
 protected:
  std::unique_ptr<octomap::OcTree> map = std::make_unique<octomap::OcTree>(kResolution);
  PlanningSession session{scratchOptions(GetParam())};
  double t = 100.0;  // s, the fake clock
  std::optional<Eigen::Vector3d> vehicle = kStart;
  uint64_t version = 0;
  std::vector<PlannedWaypoint> waypoints;
  std::vector<WaypointCancel> cancels;

  const ScratchPlanner& planner() const {
    const auto* scratch = dynamic_cast<const ScratchPlanner*>(session.planner());
    EXPECT_NE(scratch, nullptr) << "replanning: " << GetParam() << " runs another planner";
    return *scratch;
  }
  void collect() {
    for (const auto& m : session.takeOutbox().messages) {
      if (const auto* w = std::get_if<PlannedWaypoint>(&m)) waypoints.push_back(*w);
      if (const auto* c = std::get_if<WaypointCancel>(&m)) cancels.push_back(*c);
    }
  }
  void slice() {
    session.planSlice(vehicle, t);
    collect();
    t += 0.125;
    session.finishSlice(t);
    collect();
  }
  std::optional<PlannedWaypoint> next(uint64_t reached) {
    const std::size_t before = waypoints.size();
    session.onWaypointRequest({1, reached}, t);
    collect();
    for (int i = 0; i < 100 && waypoints.size() == before; ++i) slice();
    if (waypoints.size() == before) return std::nullopt;
    return waypoints.back();
  }
  /// Occupies [min, max] (z over the planning depth) and reports it as an increment.
  void wall(const Eigen::Vector2d& min, const Eigen::Vector2d& max) {
    const Eigen::Vector3d lo(min.x(), min.y(), kDepth - 1.0), hi(max.x(), max.y(), kDepth + 1.0);
    addOccupiedBox(*map, lo, hi);
    session.onMapIncrement(lo, hi, ++version);
  }
};

TEST_P(ScratchSessionTest, AnswersWaypointByWaypointUpToTheGoalWithANewTreeForEach) {
  ASSERT_TRUE(session.startQuery(makeQuery(1), *map, vehicle, t));
  EXPECT_EQ(planner().trees(), 1u);
  uint64_t reached = 0;
  for (int i = 0; i < 40 && (waypoints.empty() || !waypoints.back().is_final); ++i) {
    const Eigen::Vector3d from = waypoints.empty() ? kStart : waypoints.back().position;
    const auto w = next(reached);
    ASSERT_TRUE(w) << "no answer to request " << i + 1;
    EXPECT_EQ(w->waypoint_id, reached + 1);
    EXPECT_FALSE(w->repeat);
    EXPECT_NEAR(w->position.z(), kDepth, 1e-12);
    EXPECT_LE((w->position - from).norm(), kRange + 1e-9);
    // Each waypoint handed out moved the root: the planner started a tree there.
    EXPECT_EQ(planner().trees(), waypoints.size() + 1);
    EXPECT_LT(planner().treeIterations(), planner().iterations());
    reached = w->waypoint_id;
    vehicle = w->position;
  }
  ASSERT_TRUE(waypoints.back().is_final);
  EXPECT_LE((waypoints.back().position - kGoal).norm(), 1.0);
  EXPECT_TRUE(cancels.empty()) << cancels.front().text;
}

TEST_P(ScratchSessionTest, TreeHasOneRootAtTheVehicleFromTheStart) {
  ASSERT_TRUE(session.startQuery(makeQuery(1), *map, vehicle, t));
  TreeSnapshot tree = session.tree();
  ASSERT_EQ(tree.nodes.size(), 1u) << "the root is in the tree before the first slice";
  EXPECT_EQ(tree.root_index, 0);
  EXPECT_LT((tree.nodes[0] - kStart).norm(), 1e-12);
  slice();
  tree = session.tree();
  ASSERT_GT(tree.nodes.size(), 1u);
  EXPECT_EQ(std::count(tree.parents.begin(), tree.parents.end(), -1), 1)
      << "the valid root was added twice";
}

TEST_P(ScratchSessionTest, MapChangeStartsATreeSharingNothingButTheRoot) {
  ASSERT_TRUE(session.startQuery(makeQuery(1), *map, vehicle, t));
  const auto first = next(0);
  ASSERT_TRUE(first);
  for (int i = 0; i < 4; ++i) slice();
  const std::vector<Eigen::Vector3d> old_nodes = session.tree().nodes;
  ASSERT_GT(old_nodes.size(), 10u);
  const uint64_t trees = planner().trees();
  const uint64_t iterations = planner().iterations();

  wall({10.0, 8.0}, {10.5, 8.5});  // far from the root and the way to it
  slice();
  EXPECT_TRUE(cancels.empty()) << cancels.front().text;
  EXPECT_EQ(planner().trees(), trees + 1) << "the map change did not start a new tree";
  EXPECT_EQ(planner().treeIterations(), planner().iterations() - iterations)
      << "the new tree counts iterations of the old one";
  const TreeSnapshot tree = session.tree();
  EXPECT_LT((tree.nodes.at(static_cast<std::size_t>(tree.root_index)) - first->position).norm(),
            1e-12);
  for (std::size_t i = 0; i < tree.nodes.size(); ++i) {
    if (static_cast<int32_t>(i) == tree.root_index || (tree.nodes[i] - kGoal).norm() < 1e-9) {
      continue;  // the root, and the goal state RRTstar samples exactly
    }
    for (const Eigen::Vector3d& old : old_nodes) {
      ASSERT_GT((tree.nodes[i] - old).norm(), 1e-9) << "node reused from the old tree";
    }
  }
  // An increment that changed nothing keeps the tree.
  session.onMapIncrement(Eigen::Vector3d::Constant(1.0), Eigen::Vector3d::Zero(), ++version);
  slice();
  EXPECT_EQ(planner().trees(), trees + 1);
}

TEST_P(ScratchSessionTest, WallAcrossThePlanDropsItAndTheVehicleGoesRound) {
  ASSERT_TRUE(session.startQuery(makeQuery(1), *map, vehicle, t));
  const auto first = next(0);
  ASSERT_TRUE(first);
  const Eigen::AlignedBox3d box(Eigen::Vector3d(11.0, -6.0, kDepth - 1.0),
                                Eigen::Vector3d(12.0, 6.0, kDepth + 1.0));
  const std::vector<Eigen::Vector3d> planned = session.path().positions;
  ASSERT_GE(planned.size(), 2u);
  ASSERT_GT(planner().plannedStates(), 0u);
  bool crosses = false;
  for (std::size_t i = 1; i < planned.size(); ++i) {
    crosses = crosses || !clearOf(box, planned[i - 1], planned[i]);
  }
  ASSERT_TRUE(crosses) << "the plan does not cross where the wall will be";

  wall({11.0, -6.0}, {12.0, 6.0});
  slice();
  EXPECT_EQ(planner().plannedStates(), 0u) << "a plan through the wall was kept";
  EXPECT_TRUE(cancels.empty()) << "the way to the root was clear: " << cancels.front().text;

  uint64_t reached = first->waypoint_id;
  vehicle = first->position;
  for (int i = 0; i < 40 && !waypoints.back().is_final; ++i) {
    const Eigen::Vector3d from = waypoints.back().position;
    const auto w = next(reached);
    ASSERT_TRUE(w) << "no answer to request " << i + 2;
    EXPECT_TRUE(clearOf(box, from, w->position))
        << from.transpose() << " -> " << w->position.transpose() << " passes the wall";
    reached = w->waypoint_id;
    vehicle = w->position;
  }
  EXPECT_TRUE(waypoints.back().is_final);
}

TEST_P(ScratchSessionTest, ColumnOnTheActiveWaypointCancelsItAndReplansFromTheVehicle) {
  ASSERT_TRUE(session.startQuery(makeQuery(1), *map, vehicle, t));
  const auto first = next(0);
  ASSERT_TRUE(first);
  const Eigen::Vector3d at = first->position;
  wall({at.x() - 0.25, at.y() - 0.25}, {at.x() + 0.25, at.y() + 0.25});
  slice();
  ASSERT_EQ(cancels.size(), 1u);
  EXPECT_EQ(cancels[0].reason, CancelReason::ROOT_IN_COLLISION) << cancels[0].text;
  EXPECT_EQ(cancels[0].waypoint_id, first->waypoint_id);
  EXPECT_EQ(session.activeWaypointId(), 0u);
  EXPECT_EQ(planner().plannedStates(), 0u);
  const TreeSnapshot tree = session.tree();
  EXPECT_LT((tree.nodes.at(static_cast<std::size_t>(tree.root_index)) - *vehicle).norm(), 1e-12);
  const auto again = next(0);
  ASSERT_TRUE(again);
  EXPECT_GT(again->waypoint_id, first->waypoint_id);
}

INSTANTIATE_TEST_SUITE_P(Baselines, ScratchSessionTest, ::testing::Values("scratch", "restart"),
                         [](const auto& info) { return info.param; });

class ScratchPlannerTest : public ::testing::TestWithParam<Replanning> {};

TEST_P(ScratchPlannerTest, RootInsideTheClearanceStillGrowsATree) {
  testing::FlatWorld world;
  addOccupiedBox(*world.tree, {4.0, -3.0, 4.0}, {4.5, 3.0, 6.0});
  world.build();
  // 0.8 m from the wall's face: inside the 1.0 m clearance, outside the 0.6 m hull.
  const auto root = world.state(3.2, 0.0);
  ASSERT_FALSE(world.si->isValid(root.get()));
  auto pdef = std::make_shared<ompl::base::ProblemDefinition>(world.si);
  pdef->setStartAndGoalStates(root, world.state(1.0, 5.0), 1.0);
  pdef->setOptimizationObjective(
      std::make_shared<ompl::base::PathLengthOptimizationObjective>(world.si));
  ScratchPlanner planner(world.si, pdef, TreeSettings{}, GetParam());
  planner.reset(root.get());
  planner.solve(ompl::base::timedPlannerTerminationCondition(0.2));
  EXPECT_GT(planner.treeSize(), 1u);
  ASSERT_TRUE(planner.hasSolution());
  const auto path = planner.bestPath();
  EXPECT_TRUE(world.si->getStateSpace()->equalStates(path.front(), root.get()));
}

INSTANTIATE_TEST_SUITE_P(Baselines, ScratchPlannerTest,
                         ::testing::Values(Replanning::SCRATCH, Replanning::RESTART),
                         [](const auto& info) {
                           return std::string(info.param == Replanning::SCRATCH ? "scratch"
                                                                                : "restart");
                         });

TEST(ScratchPlannerTest, IsNoRepairPlanner) {
  testing::FlatWorld world;
  world.build();
  auto pdef = std::make_shared<ompl::base::ProblemDefinition>(world.si);
  EXPECT_THROW(ScratchPlanner(world.si, pdef, TreeSettings{}, Replanning::REPAIR),
               PlanningConfigError);
}

TEST(ScratchOptionsTest, ReplanningIsRepairScratchOrRestart) {
  SessionOptions options = scratchOptions();
  EXPECT_NO_THROW(PlanningSession{options});
  options.replanning = "repair";
  EXPECT_NO_THROW(PlanningSession{options});
  options.replanning = "restart";
  EXPECT_NO_THROW(PlanningSession{options});
  options.replanning = "rebuild";
  try {
    PlanningSession session(options);
    FAIL() << "accepted replanning 'rebuild'";
  } catch (const PlanningConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("replanning"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("restart"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace auv::planning
