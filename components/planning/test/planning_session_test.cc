// The planner's query and waypoint protocol (the paper's §2.2.1) without DDS, driven with a
// clock of the test's own: a query's lifecycle up to the goal, replaced and refused queries,
// repeated and early waypoint requests, cancels when the map blocks the root or the way to it
// (through the waypoint the vehicle still heads for), NO_SOLUTION after the time budget, and
// the views of the tree. The slices grow the tree for real (50 ms of wall time each).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "auv/planning/planning_session.h"
#include "test_maps.h"

namespace auv::planning {
namespace {

using testing::addOccupiedBox;
using testing::addRing;
using testing::kResolution;

#define EXPECT_CONTAINS(text, part) \
  EXPECT_NE(std::string(text).find(part), std::string::npos) << "'" << (text) << "'"

constexpr double kDepth = 5.0;
constexpr double kHullRadius = 0.6;
constexpr double kClearance = 1.0;
constexpr double kRange = 3.0;
const Eigen::Vector3d kStart(2.0, 0.0, kDepth);
const Eigen::Vector3d kFarStart(6.0, 0.0, kDepth);  // room behind it for the restart tests
const Eigen::Vector3d kGoal(18.0, 0.0, kDepth);
const Eigen::Vector3d kBoundsMin(0.0, -10.0, 4.0);
const Eigen::Vector3d kBoundsMax(20.0, 10.0, 6.0);

SessionOptions defaults() {
  SessionOptions o;
  o.map_resolution = kResolution;
  o.clearance.hull_radius = kHullRadius;
  o.clearance.safety_margin = kClearance - kHullRadius;
  o.range = kRange;
  o.iteration_budget = 0.05;
  o.max_distance = 8.0;
  o.max_tree_size = 3000;
  return o;
}

/// The field options the session uses for a query in the test's bounds.
OctomapDistanceFieldOptions fieldOptions() {
  OctomapDistanceFieldOptions o;
  o.max_distance = 8.0;
  o.min_corner = kBoundsMin - Eigen::Vector3d::Constant(5.0);
  o.max_corner = kBoundsMax + Eigen::Vector3d::Constant(5.0);
  return o;
}

/// One column of cells (z in [kDepth - 1, kDepth + 1]): the cell holding `at` in x and y.
Eigen::AlignedBox3d addColumn(octomap::OcTree& map, const Eigen::Vector3d& at) {
  const double x = (std::floor(at.x() / kResolution) + 0.5) * kResolution;
  const double y = (std::floor(at.y() / kResolution) + 0.5) * kResolution;
  const Eigen::Vector3d min(x - 0.25, y - 0.25, kDepth - 1.0);
  const Eigen::Vector3d max(x + 0.25, y + 0.25, kDepth + 1.0);
  addOccupiedBox(map, min, max);
  return Eigen::AlignedBox3d(min, max);
}

PlanningQuery makeQuery(uint64_t id, const Eigen::Vector3d& start, const Eigen::Vector3d& goal,
                        double time_budget = 0.0) {
  PlanningQuery q;
  q.query_id = id;
  q.start = start;
  q.goal = goal;
  q.goal_tolerance = 1.0;
  q.time_budget = time_budget;
  q.objective = PlanningObjective::VISIBILITY_COST;
  q.expected_distance = 3.0;
  q.admissible_range = 1.0;
  q.bounds_min = kBoundsMin;
  q.bounds_max = kBoundsMax;
  q.fixed_depth = kDepth;
  return q;
}

std::vector<PlannedWaypoint> waypointsIn(const PlanningSession::Outbox& out) {
  std::vector<PlannedWaypoint> found;
  for (const auto& m : out.messages) {
    if (const auto* w = std::get_if<PlannedWaypoint>(&m)) found.push_back(*w);
  }
  return found;
}

std::vector<WaypointCancel> cancelsIn(const PlanningSession::Outbox& out) {
  std::vector<WaypointCancel> found;
  for (const auto& m : out.messages) {
    if (const auto* c = std::get_if<WaypointCancel>(&m)) found.push_back(*c);
  }
  return found;
}

class PlanningSessionTest : public ::testing::Test {
 protected:
  explicit PlanningSessionTest(const SessionOptions& options = defaults()) : session(options) {}

  std::unique_ptr<octomap::OcTree> map = std::make_unique<octomap::OcTree>(kResolution);
  PlanningSession session;
  double t = 100.0;  // s, the fake clock
  std::optional<Eigen::Vector3d> vehicle = kStart;
  uint64_t version = 0;
  /// Everything the session sent since the test began, in order.
  std::vector<PlannedWaypoint> waypoints;
  std::vector<WaypointCancel> cancels;
  std::vector<std::string> warnings;

  bool start(const PlanningQuery& query) {
    const bool started = session.startQuery(query, *map, vehicle, t);
    collect();
    return started;
  }
  void request(uint64_t reached, uint64_t query_id = 1) {
    session.onWaypointRequest({query_id, reached}, t);
    collect();
  }
  /// One slice; `seconds` pass on the fake clock while the tree grows.
  void slice(double seconds = 0.125) {
    session.planSlice(vehicle, t);
    collect();
    t += seconds;
    session.finishSlice(t);
    collect();
  }
  /// Slices until the tree has a solution; false after 100.
  bool solve() {
    for (int i = 0; i < 100; ++i) {
      slice();
      if (session.planner()->hasSolution()) return true;
    }
    return false;
  }
  /// Sends the request and slices until a waypoint comes; nullopt after 100 slices.
  std::optional<PlannedWaypoint> next(uint64_t reached, uint64_t query_id = 1) {
    const std::size_t before = waypoints.size();
    request(reached, query_id);
    for (int i = 0; i < 100 && waypoints.size() == before; ++i) slice();
    if (waypoints.size() == before) return std::nullopt;
    return waypoints.back();
  }
  /// Adds a column to the map in place (an increment).
  void columnAt(const Eigen::Vector3d& at) {
    const Eigen::AlignedBox3d box = addColumn(*map, at);
    session.onMapIncrement(box.min(), box.max(), ++version);
  }
  /// Replaces the map (a full map) by `next`.
  void replaceMap(std::unique_ptr<octomap::OcTree> next) {
    session.onFullMap(*next, ++version);
    map = std::move(next);  // the session's field follows the new tree now
  }
  Eigen::Vector3d root() const {
    const TreeSnapshot tree = session.tree();
    return tree.nodes.at(static_cast<std::size_t>(tree.root_index));
  }

 private:
  void collect() {
    PlanningSession::Outbox out = session.takeOutbox();
    for (const auto& w : waypointsIn(out)) waypoints.push_back(w);
    for (const auto& c : cancelsIn(out)) cancels.push_back(c);
    for (const auto& w : out.warnings) warnings.push_back(w);
  }
};

TEST_F(PlanningSessionTest, QueryIsAnsweredWaypointByWaypointUpToTheGoal) {
  ASSERT_TRUE(start(makeQuery(1, kStart, kGoal)));
  EXPECT_TRUE(session.hasQuery());
  EXPECT_EQ(session.queryId(), 1u);
  EXPECT_TRUE(session.growing());
  request(0);
  EXPECT_TRUE(waypoints.empty()) << "answered before the tree had a solution";

  // The pending request is answered by the slice that finds a solution.
  for (int i = 0; i < 100 && waypoints.empty(); ++i) slice();
  ASSERT_EQ(waypoints.size(), 1u);
  const PlannedWaypoint first = waypoints.front();
  EXPECT_EQ(first.waypoint_id, 1u);
  EXPECT_EQ(first.query_id, 1u);
  EXPECT_FALSE(first.repeat);
  EXPECT_LE((first.position - kStart).norm(), kRange + 1e-9);
  EXPECT_NEAR(first.position.z(), kDepth, 1e-12);
  EXPECT_NEAR(first.heading,
              std::atan2(first.position.y() - kStart.y(), first.position.x() - kStart.x()), 1e-12);
  EXPECT_EQ(first.speed, 0.5);
  EXPECT_EQ(first.tolerance, 0.5);
  EXPECT_EQ(session.activeWaypointId(), first.waypoint_id);
  EXPECT_LT((root() - first.position).norm(), 1e-12) << "the waypoint becomes the root";

  uint64_t reached = first.waypoint_id;
  for (int i = 0; i < 40 && !waypoints.back().is_final; ++i) {
    vehicle = waypoints.back().position;
    const auto w = next(reached);
    ASSERT_TRUE(w) << "no answer to request " << i + 2;
    EXPECT_EQ(w->waypoint_id, reached + 1);
    EXPECT_EQ(w->query_id, 1u);
    reached = w->waypoint_id;
  }
  ASSERT_TRUE(waypoints.back().is_final);
  EXPECT_LE((waypoints.back().position - kGoal).norm(), 1.0);
  for (std::size_t i = 0; i + 1 < waypoints.size(); ++i) EXPECT_FALSE(waypoints[i].is_final);
  EXPECT_TRUE(cancels.empty()) << cancels.front().text;
}

TEST_F(PlanningSessionTest, NewQueryCancelsTheActiveWaypointAsReplacedAndStartsAtTheVehicle) {
  ASSERT_TRUE(start(makeQuery(1, kStart, kGoal)));
  const auto first = next(0);
  ASSERT_TRUE(first);
  vehicle = first->position;

  ASSERT_TRUE(start(makeQuery(2, kStart, {18.0, 8.0, kDepth})));
  ASSERT_EQ(cancels.size(), 1u);
  EXPECT_EQ(cancels[0].reason, CancelReason::QUERY_REPLACED);
  EXPECT_EQ(cancels[0].waypoint_id, first->waypoint_id);
  EXPECT_EQ(cancels[0].query_id, 1u);
  EXPECT_CONTAINS(cancels[0].text, "query 2 replaces it");
  EXPECT_EQ(session.queryId(), 2u);
  EXPECT_EQ(session.activeWaypointId(), 0u);
  EXPECT_LT((root() - *vehicle).norm(), 1e-12) << "query 2 starts at the vehicle";

  // Query 2 has no waypoint out: query 3 replaces it silently, from its start field when
  // the vehicle's position is unknown.
  vehicle.reset();
  ASSERT_TRUE(start(makeQuery(3, {4.0, 2.0, kDepth}, kGoal)));
  EXPECT_EQ(cancels.size(), 1u);
  EXPECT_LT((root() - Eigen::Vector3d(4.0, 2.0, kDepth)).norm(), 1e-12);
  EXPECT_EQ(waypoints.size(), 1u);
}

TEST_F(PlanningSessionTest, RefusedQueryIsCancelledAsPlannerError) {
  ASSERT_TRUE(start(makeQuery(1, kStart, kGoal)));
  ASSERT_TRUE(next(0));
  PlanningQuery no_tolerance = makeQuery(5, kStart, kGoal);
  no_tolerance.goal_tolerance = 0.0;
  EXPECT_FALSE(start(no_tolerance));
  // The active waypoint of the replaced query first, then the refusal.
  ASSERT_EQ(cancels.size(), 2u);
  EXPECT_EQ(cancels[0].reason, CancelReason::QUERY_REPLACED);
  EXPECT_EQ(cancels[1].reason, CancelReason::PLANNER_ERROR);
  EXPECT_EQ(cancels[1].waypoint_id, 0u);
  EXPECT_EQ(cancels[1].query_id, 5u);
  EXPECT_EQ(cancels[1].text, "query rejected: goal_tolerance must be > 0");
  EXPECT_FALSE(session.hasQuery());
  EXPECT_FALSE(session.growing());
  EXPECT_FALSE(session.planSlice(vehicle, t)) << "a slice without a query grew something";

  EXPECT_FALSE(start(makeQuery(0, kStart, kGoal)));
  ASSERT_EQ(cancels.size(), 3u);
  EXPECT_EQ(cancels[2].text, "query rejected: query_id 0 is invalid");
  PlanningQuery outside = makeQuery(6, kStart, kGoal);
  outside.fixed_depth = 9.0;  // below the bounds
  EXPECT_FALSE(start(outside));
  ASSERT_EQ(cancels.size(), 4u);
  EXPECT_EQ(cancels[3].reason, CancelReason::PLANNER_ERROR);
  EXPECT_EQ(cancels[3].query_id, 6u);
}

TEST_F(PlanningSessionTest, RepeatedRequestGetsTheActiveWaypointAgain) {
  ASSERT_TRUE(start(makeQuery(1, kStart, kGoal)));
  const auto first = next(0);
  ASSERT_TRUE(first);
  const std::size_t tree_size = session.planner()->treeSize();

  // The vehicle has not reached it (the answer was lost): the same waypoint, nothing popped.
  request(0);
  ASSERT_EQ(waypoints.size(), 2u);
  EXPECT_TRUE(waypoints[1].repeat);
  EXPECT_EQ(waypoints[1].waypoint_id, first->waypoint_id);
  EXPECT_EQ(waypoints[1].position, first->position);
  EXPECT_EQ(waypoints[1].heading, first->heading);
  EXPECT_EQ(session.planner()->treeSize(), tree_size);
  EXPECT_LT((root() - first->position).norm(), 1e-12);
  request(first->waypoint_id + 7);  // not the active one either
  ASSERT_EQ(waypoints.size(), 3u);
  EXPECT_EQ(waypoints[2].waypoint_id, first->waypoint_id);

  // Reached: the next one.
  request(first->waypoint_id);
  ASSERT_EQ(waypoints.size(), 4u);
  EXPECT_FALSE(waypoints[3].repeat);
  EXPECT_EQ(waypoints[3].waypoint_id, first->waypoint_id + 1);
  EXPECT_LE((waypoints[3].position - first->position).norm(), kRange + 1e-9);
}

// A restarted planner meets a mission handler in the middle of a query: the handler must learn
// that the query is gone (it re-issues it) instead of waiting for waypoints that never come.
TEST_F(PlanningSessionTest, RequestForAQueryPlannedBeforeARestartIsCancelledAsUnknown) {
  request(7, 3);  // reached waypoint 7 of query 3: planned by the planner before this one
  EXPECT_TRUE(waypoints.empty());
  ASSERT_EQ(cancels.size(), 1u);
  EXPECT_EQ(cancels[0].reason, CancelReason::UNKNOWN_QUERY);
  EXPECT_EQ(cancels[0].query_id, 3u);
  EXPECT_EQ(cancels[0].waypoint_id, 0u);
  EXPECT_CONTAINS(cancels[0].text, "no query 3");
}

TEST_F(PlanningSessionTest, FirstRequestRepeatedWithoutItsQueryIsCancelledAsUnknown) {
  request(0, 5);  // may have overtaken its query: kept
  t += 0.5 * PlanningSession::kLostQueryAfter;
  request(0, 5);  // repeated soon: still kept
  EXPECT_TRUE(cancels.empty());
  t += PlanningSession::kLostQueryAfter;
  request(0, 5);  // repeated long after: the query is lost
  ASSERT_EQ(cancels.size(), 1u);
  EXPECT_EQ(cancels[0].reason, CancelReason::UNKNOWN_QUERY);
  EXPECT_CONTAINS(cancels[0].text, "lost");
  // The re-issued query is planned as usual.
  ASSERT_TRUE(start(makeQuery(6, kStart, kGoal)));
  request(0, 6);
  for (int i = 0; i < 100 && waypoints.empty(); ++i) slice();
  ASSERT_EQ(waypoints.size(), 1u);
  EXPECT_EQ(waypoints[0].query_id, 6u);
  EXPECT_EQ(cancels.size(), 1u);
}

TEST_F(PlanningSessionTest, RequestThatOvertakesItsQueryIsAnsweredOnceItStarts) {
  request(0, 2);  // no query yet
  EXPECT_TRUE(waypoints.empty());
  ASSERT_TRUE(start(makeQuery(2, kStart, kGoal)));
  for (int i = 0; i < 100 && waypoints.empty(); ++i) slice();
  ASSERT_EQ(waypoints.size(), 1u) << "the early request was never answered";
  EXPECT_EQ(waypoints[0].query_id, 2u);

  // A stale request of an older query: a warning, no answer.
  request(0, 1);
  EXPECT_EQ(waypoints.size(), 1u);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_CONTAINS(warnings[0], "waypoint request for query 1, older than the one planned (2)");

  // Kept for the next query only: query 3 starts instead of 4, and 4's request is gone.
  request(0, 4);
  ASSERT_TRUE(start(makeQuery(3, kStart, kGoal)));
  ASSERT_TRUE(solve());
  ASSERT_TRUE(start(makeQuery(4, kStart, kGoal)));
  ASSERT_TRUE(solve());
  slice();
  EXPECT_EQ(waypoints.size(), 1u) << "a request was answered for a query that did not get it";
  EXPECT_EQ(warnings.size(), 1u);
}

/// Starts a query at kFarStart on an empty map, takes its first waypoint and puts the vehicle
/// `short_of` m short of it on the line from the start.
class RestartTest : public PlanningSessionTest {
 protected:
  void SetUp() override {
    vehicle = kFarStart;
    ASSERT_TRUE(start(makeQuery(1, kFarStart, kGoal)));
    const auto w = next(0);
    ASSERT_TRUE(w);
    first = *w;
  }
  void moveShortOfTheWaypoint(double short_of) {
    vehicle = first.position - short_of * (first.position - kFarStart).normalized();
  }
  /// After the cancel: the tree restarted at the vehicle and the next request is answered from
  /// there.
  void expectReplanFromTheVehicle(uint64_t iterations_before) {
    EXPECT_EQ(session.activeWaypointId(), 0u);
    EXPECT_LT((root() - *vehicle).norm(), 1e-12) << "root at " << root().transpose();
    EXPECT_GE(session.tree().iterations, iterations_before) << "iterations count the whole query";
    const auto w = next(0);
    ASSERT_TRUE(w);
    EXPECT_GT(w->waypoint_id, first.waypoint_id);
    EXPECT_LE((w->position - *vehicle).norm(), kRange + 1e-9) << "not a child of the new root";
    EXPECT_EQ(cancels.size(), 1u);
  }

  PlannedWaypoint first;
};

TEST_F(RestartTest, ColumnOnTheWayToTheActiveWaypointCancelsItAsApproachInCollision) {
  // Behind the start (navigation put it there): a column half-way leaves both ends clear.
  moveShortOfTheWaypoint(3.8);
  const uint64_t iterations = session.tree().iterations;
  columnAt(0.5 * (first.position + *vehicle));
  EXPECT_TRUE(cancels.empty()) << "cancelled before the slice re-checked the tree";
  slice();
  ASSERT_EQ(cancels.size(), 1u);
  EXPECT_EQ(cancels[0].reason, CancelReason::APPROACH_IN_COLLISION) << cancels[0].text;
  EXPECT_EQ(cancels[0].waypoint_id, first.waypoint_id);
  EXPECT_EQ(cancels[0].query_id, 1u);
  EXPECT_CONTAINS(cancels[0].text, "segment vehicle -> root at (");
  EXPECT_CONTAINS(cancels[0].text, "closer than 0.6 m to the map (version 1)");
  expectReplanFromTheVehicle(iterations);
}

TEST_F(RestartTest, ColumnOnTheActiveWaypointCancelsItAsRootInCollision) {
  moveShortOfTheWaypoint(2.2);
  const uint64_t iterations = session.tree().iterations;
  columnAt(first.position);
  slice();
  ASSERT_EQ(cancels.size(), 1u);
  EXPECT_EQ(cancels[0].reason, CancelReason::ROOT_IN_COLLISION) << cancels[0].text;
  EXPECT_EQ(cancels[0].waypoint_id, first.waypoint_id);
  EXPECT_CONTAINS(cancels[0].text, "root at (");
  EXPECT_CONTAINS(cancels[0].text, "closer than 1 m to the map");
  expectReplanFromTheVehicle(iterations);
}

TEST_F(PlanningSessionTest, WithoutAnActiveWaypointAWallByTheRootRestartsNothing) {
  ASSERT_TRUE(start(makeQuery(1, kStart, kGoal)));
  ASSERT_TRUE(solve());
  // Within the clearance of the root (where the vehicle holds), not on it.
  columnAt(kStart + Eigen::Vector3d(-0.75, 0.75, 0.0));
  slice();
  EXPECT_TRUE(cancels.empty()) << cancels.front().text;
  EXPECT_LT((root() - kStart).norm(), 1e-12) << "the tree was restarted";
  const auto w = next(0);
  ASSERT_TRUE(w);
  EXPECT_TRUE(cancels.empty());
}

// The vehicle still heads for the previous waypoint A when B is sent: its way to the root B
// is checked through A (round the corner), and straight once it has reached A.
TEST_F(PlanningSessionTest, WayToTheRootIsCheckedThroughTheWaypointTheVehicleHeadsFor) {
  // A pair A -> B long enough for a column beside both legs of the corner (the edges are
  // random: a new query when a path has none).
  std::optional<PlannedWaypoint> a;
  std::optional<PlannedWaypoint> b;
  for (uint64_t id = 1; id <= 20 && !b; ++id) {
    ASSERT_TRUE(start(makeQuery(id, kStart, kGoal)));
    a = next(0, id);
    ASSERT_TRUE(a);
    while (!a->is_final && !b) {
      const auto w = next(a->waypoint_id, id);
      ASSERT_TRUE(w);
      if ((w->position - a->position).norm() >= 2.5 && !w->is_final) {
        b = w;
      } else {
        a = w;
      }
    }
  }
  ASSERT_TRUE(b) << "no edge of 2.5 m on 20 paths";
  cancels.clear();  // of the queries replaced
  const Eigen::Vector3d A = a->position;
  const Eigen::Vector3d B = b->position;
  // The vehicle 5 m aside A (on the side nearer y = 0), the column where V -> B is farthest
  // from both legs V -> A and A -> B.
  Eigen::Vector3d side(-(B - A).y(), (B - A).x(), 0.0);
  side.normalize();
  if (std::abs((A - 5.0 * side).y()) < std::abs((A + 5.0 * side).y())) side = -side;
  const Eigen::Vector3d V = A + 5.0 * side;
  ASSERT_TRUE((V.array() > kBoundsMin.array()).all() && (V.array() < kBoundsMax.array()).all())
      << "V at " << V.transpose();
  const double s = 5.0 / (5.0 + (B - A).norm());
  vehicle = V;
  octomap::OcTree expected = *map;
  const Eigen::Vector3d column = V + s * (B - V);
  addColumn(expected, column);
  const OctomapDistanceField check(&expected, fieldOptions());
  ASSERT_GE(check.distance(B), kClearance) << "the column would make the root invalid";
  ASSERT_TRUE(hullPassesAlong(check, V, A, kHullRadius, 0.25));
  ASSERT_TRUE(hullPassesAlong(check, A, B, kHullRadius, 0.25));
  ASSERT_FALSE(hullPassesAlong(check, V, B, kHullRadius, 0.25));

  columnAt(column);
  slice();
  EXPECT_TRUE(cancels.empty()) << cancels.front().text;

  // At A (within tolerance) A is forgotten: from V again, the straight way is blocked.
  vehicle = A;
  columnAt({19.0, 9.0, kDepth});  // far away: only for the re-check
  slice();
  EXPECT_TRUE(cancels.empty()) << cancels.front().text;
  vehicle = V;
  columnAt({19.0, -9.0, kDepth});
  slice();
  ASSERT_EQ(cancels.size(), 1u);
  EXPECT_EQ(cancels[0].reason, CancelReason::APPROACH_IN_COLLISION) << cancels[0].text;
  EXPECT_EQ(cancels[0].waypoint_id, b->waypoint_id);
}

/// A small tree limit, so that a tree without a solution fills up quickly.
class NoSolutionTest : public PlanningSessionTest {
 protected:
  static SessionOptions smallTree() {
    SessionOptions o = defaults();
    o.max_tree_size = 200;
    return o;
  }
  NoSolutionTest() : PlanningSessionTest(smallTree()) {}
};

TEST_F(NoSolutionTest, EnclosedGoalIsCancelledOnceTheBudgetIsSpentThenAnsweredWhenItOpens) {
  const Eigen::Vector3d goal(15.0, 0.0, kDepth);
  addRing(*map, goal, kDepth);
  ASSERT_TRUE(start(makeQuery(1, kStart, goal, 1.0)));
  request(0);
  // 8 slices of 1/8 s: exactly the budget, not more.
  for (int i = 0; i < 8; ++i) slice(0.125);
  EXPECT_TRUE(cancels.empty()) << cancels.front().text;
  slice(0.125);
  ASSERT_EQ(cancels.size(), 1u);
  EXPECT_EQ(cancels[0].reason, CancelReason::NO_SOLUTION);
  EXPECT_EQ(cancels[0].waypoint_id, 0u);
  EXPECT_EQ(cancels[0].query_id, 1u);
  EXPECT_CONTAINS(cancels[0].text, "no solution for 1.125 s (budget 1 s)");

  // Reported once; the full tree keeps being regrown from the same root.
  uint64_t iterations = session.tree().iterations;
  for (int i = 0; i < 10; ++i) {
    slice();
    EXPECT_LE(session.planner()->treeSize(), 200u);
    EXPECT_LT((root() - kStart).norm(), 1e-12);
    EXPECT_GT(session.tree().iterations, iterations);
    iterations = session.tree().iterations;
  }
  EXPECT_EQ(cancels.size(), 1u);
  EXPECT_TRUE(waypoints.empty());

  // The way opens: the request still pending is answered.
  replaceMap(std::make_unique<octomap::OcTree>(kResolution));
  for (int i = 0; i < 100 && waypoints.empty(); ++i) slice();
  ASSERT_EQ(waypoints.size(), 1u) << "the pending request was never answered";
  EXPECT_EQ(waypoints[0].query_id, 1u);
  EXPECT_EQ(cancels.size(), 1u);
}

TEST_F(PlanningSessionTest, BudgetCountsFromTheLastSolution) {
  const Eigen::Vector3d goal(15.0, 0.0, kDepth);
  ASSERT_TRUE(start(makeQuery(1, kStart, goal, 1.0)));
  const auto first = next(0);
  ASSERT_TRUE(first);
  for (int i = 0; i < 6; ++i) slice(0.5);  // 3 s with a solution: older than its budget
  EXPECT_TRUE(cancels.empty()) << cancels.front().text;

  // The goal is enclosed: every solution goes, the budget runs from the last one.
  auto ring = std::make_unique<octomap::OcTree>(kResolution);
  addRing(*ring, goal, kDepth);
  replaceMap(std::move(ring));
  for (int i = 0; i < 8; ++i) slice(0.125);
  ASSERT_FALSE(session.planner()->hasSolution());
  EXPECT_TRUE(cancels.empty()) << cancels.front().text;
  slice(0.125);
  ASSERT_EQ(cancels.size(), 1u);
  EXPECT_EQ(cancels[0].reason, CancelReason::NO_SOLUTION);
  EXPECT_EQ(cancels[0].waypoint_id, first->waypoint_id) << "the active waypoint is named";

  // Open again, then enclosed again: reported again.
  replaceMap(std::make_unique<octomap::OcTree>(kResolution));
  ASSERT_TRUE(solve());
  ring = std::make_unique<octomap::OcTree>(kResolution);
  addRing(*ring, goal, kDepth);
  replaceMap(std::move(ring));
  for (int i = 0; i < 9; ++i) slice(0.125);
  EXPECT_EQ(cancels.size(), 2u);
}

/// detour_hold of 2 s at a cost ratio of 1.6, path-length queries (Eq. (1) would reward the
/// wall the tests put up) in bounds 60 m wide, so that a wall leaves a long way round.
class DetourHoldTest : public PlanningSessionTest {
 protected:
  static SessionOptions holding() {
    SessionOptions o = defaults();
    o.detour_hold = 2.0;
    o.detour_factor = 1.6;
    o.max_tree_size = 1000000;  // a full tree ends the hold (DetourHoldFullTreeTest)
    return o;
  }
  explicit DetourHoldTest(const SessionOptions& options = holding())
      : PlanningSessionTest(options) {}

  /// Starts the query, takes the first waypoint and grows the tree to a near-straight path.
  PlannedWaypoint goUnderway() {
    PlanningQuery query = makeQuery(1, kStart, kGoal);
    query.objective = PlanningObjective::PATH_LENGTH;
    query.bounds_min.y() = -30.0;
    query.bounds_max.y() = 30.0;
    EXPECT_TRUE(start(query));
    const auto first = next(0);
    EXPECT_TRUE(first);
    vehicle = first->position;
    for (int i = 0; i < 20; ++i) slice();
    return *first;
  }
  /// A wall across the straight way at x = 10, open only at y > 20: the way round costs
  /// about three times the straight one.
  static std::unique_ptr<octomap::OcTree> walled() {
    auto wall = std::make_unique<octomap::OcTree>(kResolution);
    addOccupiedBox(*wall, {9.5, -31.0, 3.0}, {10.5, 20.0, 7.0});
    return wall;
  }
  /// Puts the wall up and asks for the next waypoint: the hold starts. Returns when.
  double wallUpAndRequest(const PlannedWaypoint& first) {
    const double cut = t;
    replaceMap(walled());
    slice();
    EXPECT_TRUE(warned("waits up to 2 s for a shorter way"));
    request(first.waypoint_id);
    return cut;
  }
  bool warned(const std::string& part) const {
    return std::any_of(warnings.begin(), warnings.end(),
                       [&](const std::string& w) { return w.find(part) != std::string::npos; });
  }
};

TEST_F(DetourHoldTest, AMuchLongerDetourWaitsForItsHoldThenIsTaken) {
  const PlannedWaypoint first = goUnderway();
  const double cost_before = session.path().cost;
  const double cut = wallUpAndRequest(first);
  while (t < cut + 1.8) {
    slice();
    ASSERT_EQ(waypoints.size(), 1u)
        << "a waypoint came " << t - cut << " s into the hold: " << warnings.back();
  }
  for (int i = 0; i < 100 && waypoints.size() == 1; ++i) slice();
  ASSERT_EQ(waypoints.size(), 2u);
  EXPECT_GE(t, cut + 2.0);
  EXPECT_TRUE(warned("no shorter way within detour_hold: taking the detour"));
  EXPECT_GT(session.path().cost, 1.6 * cost_before) << "the only way is the long one";
  EXPECT_TRUE(cancels.empty()) << cancels.front().text;
}

TEST_F(DetourHoldTest, AWayBackEndsTheHoldAtOnce) {
  const PlannedWaypoint first = goUnderway();
  const double cut = wallUpAndRequest(first);
  // The wall was a false return: the next map clears it and the tree regrows the short way.
  replaceMap(std::make_unique<octomap::OcTree>(kResolution));
  for (int i = 0; i < 100 && waypoints.size() == 1; ++i) slice();
  ASSERT_EQ(waypoints.size(), 2u);
  EXPECT_LT(t, cut + 2.0) << "held the whole time although a short way was found";
  EXPECT_TRUE(warned("found a way of cost"));
}

/// The same with a tree limit the hold reaches: a full tree grows no way back.
class DetourHoldFullTreeTest : public DetourHoldTest {
 protected:
  static SessionOptions smallTree() {
    SessionOptions o = holding();
    o.max_tree_size = 1500;  // full again within the hold
    return o;
  }
  DetourHoldFullTreeTest() : DetourHoldTest(smallTree()) {}
};

TEST_F(DetourHoldFullTreeTest, AFullTreeEndsTheHold) {
  const PlannedWaypoint first = goUnderway();
  const double cut = wallUpAndRequest(first);
  for (int i = 0; i < 100 && waypoints.size() == 1; ++i) slice();
  ASSERT_EQ(waypoints.size(), 2u);
  EXPECT_LT(t, cut + 2.0) << "held on with a tree that could not grow";
  EXPECT_TRUE(warned("the tree is full")) << warnings.back();
}

/// detour_hold 0 (the default): the paper's behaviour.
class NoDetourHoldTest : public DetourHoldTest {
 protected:
  static SessionOptions noHold() {
    SessionOptions o = holding();
    o.detour_hold = 0.0;
    return o;
  }
  NoDetourHoldTest() : DetourHoldTest(noHold()) {}
};

TEST_F(NoDetourHoldTest, TheDetourIsTakenAtOnce) {
  const PlannedWaypoint first = goUnderway();
  const double cut = t;
  replaceMap(walled());
  // Answered as soon as the tree has a way again, well within the 2 s a hold would last.
  ASSERT_TRUE(next(first.waypoint_id));
  EXPECT_LT(t, cut + 2.0);
  EXPECT_TRUE(warnings.empty()) << warnings.front();
}

TEST_F(PlanningSessionTest, TreeAndPathSnapshotsAgree) {
  EXPECT_TRUE(session.tree().nodes.empty());
  EXPECT_TRUE(session.path().positions.empty());
  ASSERT_TRUE(start(makeQuery(1, kStart, kGoal)));
  ASSERT_TRUE(solve());
  const TreeSnapshot tree = session.tree();
  const PathSnapshot path = session.path();
  const auto n = static_cast<int32_t>(tree.nodes.size());
  ASSERT_EQ(tree.root_index, 0);
  EXPECT_EQ(tree.parents[0], -1);
  EXPECT_EQ(tree.costs[0], 0.0);
  EXPECT_EQ(static_cast<std::size_t>(n), session.planner()->treeSize());
  for (int32_t i = 1; i < n; ++i) {
    ASSERT_GE(tree.parents[i], 0);
    ASSERT_LT(tree.parents[i], i) << "a child before its parent";
    EXPECT_GE(tree.costs[i], tree.costs[tree.parents[i]] - 1e-9);
  }
  for (int32_t s : tree.solution_indices) {
    EXPECT_LE((tree.nodes[s] - kGoal).norm(), 1.0);
  }
  ASSERT_NE(std::find(tree.solution_indices.begin(), tree.solution_indices.end(),
                      tree.best_solution_index),
            tree.solution_indices.end());
  std::vector<Eigen::Vector3d> chain;
  for (int32_t i = tree.best_solution_index; i >= 0; i = tree.parents[i]) {
    chain.insert(chain.begin(), tree.nodes[i]);
  }
  ASSERT_EQ(chain.size(), path.positions.size());
  for (std::size_t i = 0; i < chain.size(); ++i) EXPECT_EQ(chain[i], path.positions[i]);
  EXPECT_GE(path.cost, tree.costs[tree.best_solution_index] - 1e-9);
  EXPECT_TRUE(std::isfinite(path.cost));
  EXPECT_GE(tree.iterations + 1, static_cast<uint64_t>(n));
}

TEST(HullPassesAlongTest, HullMayLeaveTheWallButNeverApproachIt) {
  octomap::OcTree map(kResolution);
  addColumn(map, {10.25, 0.25, kDepth});  // the cell [10, 10.5] x [0, 0.5]
  const OctomapDistanceField field(&map, fieldOptions());
  const double step = 0.25;
  EXPECT_FALSE(hullPassesAlong(field, {5, 0.25, kDepth}, {15, 0.25, kDepth}, kHullRadius, step));
  EXPECT_TRUE(hullPassesAlong(field, {5, 2.0, kDepth}, {15, 2.0, kDepth}, kHullRadius, step));
  // 0.2 m from the cell: leaving it passes, coming back or going in does not.
  const Eigen::Vector3d inside(10.7, 0.25, kDepth);
  EXPECT_TRUE(hullPassesAlong(field, inside, {14, 0.25, kDepth}, kHullRadius, step));
  EXPECT_FALSE(hullPassesAlong(field, {14, 0.25, kDepth}, inside, kHullRadius, step));
  EXPECT_FALSE(hullPassesAlong(field, inside, {10.55, 0.25, kDepth}, kHullRadius, step));
}

TEST(SessionOptionsTest, SamplingSharesAboveOneAreRefusedNamingBoth) {
  SessionOptions options = defaults();
  options.goal_bias = 0.5;
  options.narrow_passage_bias = 0.6;
  try {
    PlanningSession session(options);
    FAIL() << "accepted goal_bias 0.5 + narrow_passage_bias 0.6";
  } catch (const PlanningConfigError& error) {
    EXPECT_CONTAINS(error.what(), "goal_bias + narrow_passage_bias");
  }
}

}  // namespace
}  // namespace auv::planning
