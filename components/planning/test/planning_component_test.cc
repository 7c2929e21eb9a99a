// The planning component on real DDS, the component and the test's mission handler on
// different vendors (both pairings where a test runs them one after the other): waypoints
// across a wall keep the clearance; a late joiner gets the map; a new obstacle prunes the tree
// and the waypoints go around it; a colliding root or approach cancels and replans from the
// vehicle; a sequence gap calls map/request_full; a new query cancels the active waypoint; an
// enclosed goal cancels with NO_SOLUTION; every planner/tree received is well formed. Each
// test on its own domain id (90..99 and 83, test/README.md).
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <tuple>

#include "component_fixture.h"

namespace auv::planning {
namespace {

using namespace testing;  // auv::planning::testing: the fixture

#define EXPECT_VIEWS_WELL_FORMED(harness)    \
  EXPECT_TRUE((harness).view_errors.empty()) \
      << (harness).view_errors.size() << " bad views, first: " << (harness).view_errors.front()

/// Runs `scenario` for both vendor pairings on `domain`, one after the other.
template <class Scenario>
void forEachPairing(int domain, Scenario scenario) {
  for (const Pairing& pairing : pairings()) {
    SCOPED_TRACE(describe(pairing));
    scenario(pairing, domain);
  }
}

std::string describe(const std::vector<msg::WaypointCancel>& cancels) {
  std::ostringstream out;
  for (const auto& c : cancels) {
    out << "[waypoint " << c.waypoint_id() << " query " << c.query_id() << " reason " << c.reason()
        << ": " << c.reason_text() << "] ";
  }
  return out.str();
}

// A start with room behind it: the restart tests put the vehicle short of the first waypoint.
const Eigen::Vector3d kFarStart(6.0, 0.0, kDepth);

TEST(PlanningComponentTest, WaypointsCrossTheWallKeepingTheClearance) {
  PlanningHarness harness(Vendor::CYCLONEDDS, Vendor::FASTDDS, 90);
  const octomap::OcTree map = wallMap();
  const Occupied occupied(map);
  ASSERT_TRUE(harness.startQuery(map));

  std::vector<Eigen::Vector3d> visited{kStart};
  ASSERT_TRUE(harness.followToGoal(1, 0, &visited));
  for (std::size_t i = 1; i < visited.size(); ++i) {
    EXPECT_NEAR(visited[i].z(), kDepth, 1e-9);
    EXPECT_GE(occupied.distance(visited[i]), kClearance - kQuantisation)
        << "waypoint " << i << " at " << visited[i].transpose();
    EXPECT_GE(occupied.segment(visited[i - 1], visited[i]), kClearance - kQuantisation)
        << "segment to waypoint " << i;
  }
  EXPECT_LE((visited.back() - kGoal).norm(), 1.0);
  EXPECT_TRUE(harness.cancels.empty()) << describe(harness.cancels);
  EXPECT_VIEWS_WELL_FORMED(harness);
}

// A query starting inside the clearance (the vehicle drifted within 1 m of a rock): OMPL's
// start-state input skips such starts, which once left the planner without a tree and crashed
// the process at the next map update. The tree is rooted there anyway and leaves the rock.
TEST(PlanningComponentTest, StartInsideTheClearanceStillPlansAwayFromTheRock) {
  PlanningHarness harness(Vendor::CYCLONEDDS, Vendor::FASTDDS, 150);
  octomap::OcTree map = wallMap();
  addColumn(map, kStart + Eigen::Vector3d(0.75, 0.75, 0.0));  // the cell [2.5, 3) x [0.5, 1)
  const auto rock = [](const Eigen::Vector3d& p) {            // distance to that cell's box
    return Eigen::Vector2d(std::max({2.5 - p.x(), 0.0, p.x() - 3.0}),
                           std::max({0.5 - p.y(), 0.0, p.y() - 1.0}))
        .norm();
  };
  ASSERT_GT(rock(kStart), kHullRadius);
  ASSERT_LT(rock(kStart), kClearance);
  ASSERT_TRUE(harness.startQuery(map));
  // A map update re-checks the tree (where the crash was), then the vehicle goes to the goal.
  octomap::OcTree grown = map;
  addColumn(grown, {10.0, -6.0, kDepth});
  ASSERT_TRUE(harness.publishMapAndWait(makeUpdate(grown, 2, 1)));
  std::vector<Eigen::Vector3d> visited{kStart};
  ASSERT_TRUE(harness.followToGoal(1, 0, &visited));
  EXPECT_LE((visited.back() - kGoal).norm(), 1.0);
  EXPECT_GE(rock(visited[1]), rock(kStart)) << "the first waypoint goes towards the rock";
}

TEST(PlanningComponentTest, ObstacleOnTheWayToTheActiveWaypointCancelsIt) {
  PlanningHarness harness(Vendor::FASTDDS, Vendor::CYCLONEDDS, 91);
  const octomap::OcTree map = wallMap();
  ASSERT_TRUE(harness.startQuery(map));
  ASSERT_TRUE(harness.requestWaypoint(0));
  const msg::Waypoint first = harness.waypoints.back();
  const Eigen::Vector3d root = toVector(first.position());
  ASSERT_TRUE(harness.cancels.empty());

  // An obstacle column on the segment vehicle -> waypoint, kept off the vehicle itself where
  // the segment allows, so the planner can restart from there.
  const double length = (root - kStart).norm();
  const double along = std::min(length, std::max(0.5 * length, kClearance + 0.6));
  const Eigen::Vector3d obstacle = kStart + (root - kStart).normalized() * along;
  octomap::OcTree diff(kResolution);
  addOccupiedBox(diff, obstacle - Eigen::Vector3d(0.25, 0.25, 1.0),
                 obstacle + Eigen::Vector3d(0.25, 0.25, 1.0));
  ASSERT_GT(diff.getNumLeafNodes(), 0u);
  harness.publishMap(makeUpdate(diff, 2, 1));

  ASSERT_TRUE(harness.spinUntil([&] { return !harness.cancels.empty(); }));
  const msg::WaypointCancel& cancel = harness.cancels.front();
  EXPECT_EQ(cancel.query_id(), 1u);
  EXPECT_EQ(cancel.waypoint_id(), first.waypoint_id());
  EXPECT_TRUE(cancel.reason() == msg::CANCEL_REASON_APPROACH_IN_COLLISION ||
              cancel.reason() == msg::CANCEL_REASON_ROOT_IN_COLLISION)
      << "reason " << cancel.reason() << ": " << cancel.reason_text();
  EXPECT_FALSE(cancel.reason_text().empty());
}

// The map was published (transient local, keep last 1, as the mapping component does) before
// the planner existed: the planner's replica reaches that version and plans around its wall.
TEST(PlanningComponentTest, LateJoiningPlannerGetsThePublishedMapAndPlansAroundIt) {
  forEachPairing(92, [](const Pairing& pairing, int domain) {
    PlanningHarness harness(pairing.planner, pairing.handler, domain, /*start_planner=*/false);
    const octomap::OcTree wall = wallMap();
    harness.publishMap(makeUpdate(octomap::OcTree(kResolution), 1, 0));
    harness.publishMap(makeUpdate(wall, 2, 0));  // the writer keeps only this one
    harness.spinFor(100ms);
    harness.startPlanner();
    ASSERT_TRUE(harness.spinUntil([&] { return harness.planning().mapSequence() == 2; }))
        << "replica at version " << harness.planning().mapSequence();

    ASSERT_TRUE(harness.startQuery(makeQuery(1, kStart, kGoal)));
    std::vector<Eigen::Vector3d> visited{kStart};
    ASSERT_TRUE(harness.followToGoal(1, 0, &visited));
    // The straight line crosses the wall: only a planner holding the map keeps the clearance.
    const Occupied occupied(wall);
    EXPECT_LT(occupied.segment(kStart, kGoal), kClearance - kQuantisation);
    EXPECT_GE(occupied.polyline(visited), kClearance - kQuantisation);
    EXPECT_LE((visited.back() - kGoal).norm(), 1.0);
    EXPECT_EQ(harness.planning().mapSequence(), 2u);
    EXPECT_TRUE(harness.cancels.empty()) << describe(harness.cancels);
    EXPECT_VIEWS_WELL_FORMED(harness);
  });
}

// Planned on an empty map (unknown = free), then a wall appears across the path: the tree
// loses exactly what the wall blocks (the rest and the root stay: a repair, not a restart),
// the path and the waypoints go around, the goal is reached, and nothing is cancelled even
// though the query is older than its time budget when its solutions disappear.
TEST(PlanningComponentTest, NewObstacleAcrossThePathPrunesTheTreeAndWaypointsGoAround) {
  forEachPairing(93, [](const Pairing& pairing, int domain) {
    constexpr double kBudget = 1.0;
    PlanningHarness harness(pairing.planner, pairing.handler, domain);
    const octomap::OcTree wall = wallMap();
    const Occupied occupied(wall);
    ASSERT_TRUE(harness.waitForPlannerReaders());
    ASSERT_TRUE(harness.publishMapAndWait(makeUpdate(octomap::OcTree(kResolution), 1, 0)));
    const int64_t query_sent = systemNowNs();
    ASSERT_TRUE(harness.startQuery(makeQuery(1, kStart, kGoal, kBudget)));
    const auto empty_path = harness.waitForPath(query_sent, 1);
    ASSERT_TRUE(empty_path);
    ASSERT_LT(occupied.polyline(pathPositions(*empty_path)), kClearance - kQuantisation)
        << "the path on the empty map should cross the wall-to-be";

    ASSERT_TRUE(harness.requestWaypoint(0));
    const msg::Waypoint first = harness.waypoints.back();
    const Eigen::Vector3d root = toVector(first.position());
    ASSERT_TRUE(harness.moveVehicle(root));
    harness.spinFor(std::chrono::milliseconds(static_cast<int>(1000 * kBudget) + 200));

    const auto before = harness.waitForTree(systemNowNs(), 1);
    ASSERT_TRUE(before);
    std::size_t blocked_before = 0;
    std::vector<Eigen::Vector3d> near_side;  // far from the wall on the vehicle's side
    for (const auto& node : before->nodes()) {
      const Eigen::Vector3d p = toVector(node);
      if (!occupied.clear(p)) ++blocked_before;
      if (p.x() < 7.0 && p.x() > root.x()) near_side.push_back(p);
    }
    ASSERT_GT(blocked_before, 0u) << "the tree should have grown where the wall appears";
    ASSERT_GT(near_side.size(), 10u);

    harness.publishMap(makeUpdate(wall, 2, 1));
    ASSERT_TRUE(harness.spinUntil([&] { return harness.planning().mapSequence() == 2; }));
    const int64_t applied = systemNowNs();

    const auto after = harness.waitForTree(applied, 1);
    ASSERT_TRUE(after);
    std::size_t blocked_nodes = 0;
    std::size_t blocked_edges = 0;
    std::set<std::tuple<double, double, double>> kept;
    for (std::size_t i = 0; i < after->nodes().size(); ++i) {
      const Eigen::Vector3d p = toVector(after->nodes()[i]);
      kept.emplace(p.x(), p.y(), p.z());
      if (!occupied.clear(p)) ++blocked_nodes;
      const int32_t parent = after->parents()[i];
      if (parent >= 0 &&
          occupied.segment(toVector(after->nodes()[parent]), p) < kClearance - kQuantisation) {
        ++blocked_edges;
      }
    }
    EXPECT_EQ(blocked_nodes, 0u) << "of " << after->nodes().size() << " nodes";
    EXPECT_EQ(blocked_edges, 0u);
    ASSERT_GE(after->root_index(), 0);
    EXPECT_LT((toVector(after->nodes()[after->root_index()]) - root).norm(), 1e-9)
        << "the root moved: the tree was restarted, not repaired";
    std::size_t survived = 0;
    for (const auto& p : near_side) survived += kept.count({p.x(), p.y(), p.z()});
    EXPECT_GT(2 * survived, near_side.size())
        << survived << " of " << near_side.size() << " nodes away from the wall survived";

    const auto around = harness.waitForPath(applied, 1);
    ASSERT_TRUE(around);
    EXPECT_GE(occupied.polyline(pathPositions(*around)), kClearance - kQuantisation);

    std::vector<Eigen::Vector3d> visited{root};
    ASSERT_TRUE(harness.followToGoal(1, first.waypoint_id(), &visited));
    EXPECT_GE(occupied.polyline(visited), kClearance - kQuantisation);
    EXPECT_LE((visited.back() - kGoal).norm(), 1.0);
    EXPECT_TRUE(harness.cancels.empty()) << describe(harness.cancels);
    EXPECT_VIEWS_WELL_FORMED(harness);
  });
}

/// The restart scenario: the first waypoint is out, the vehicle is `short_of` m short of it
/// (on the line start -> waypoint), and `obstacle(root, vehicle)` appears as an increment;
/// expects a cancel for `reason`, then a replan from the vehicle's position around it.
template <class Obstacle>
void restartScenario(const Pairing& pairing, int domain, double short_of, Obstacle obstacle,
                     msg::CancelReason reason) {
  PlanningHarness harness(pairing.planner, pairing.handler, domain);
  ASSERT_TRUE(harness.waitForPlannerReaders());
  ASSERT_TRUE(harness.publishMapAndWait(makeUpdate(octomap::OcTree(kResolution), 1, 0)));
  ASSERT_TRUE(harness.moveVehicle(kFarStart));
  ASSERT_TRUE(harness.startQuery(makeQuery(1, kFarStart, kGoal)));
  ASSERT_TRUE(harness.requestWaypoint(0));
  const msg::Waypoint first = harness.waypoints.back();
  const Eigen::Vector3d root = toVector(first.position());
  const Eigen::Vector3d vehicle = root - short_of * (root - kFarStart).normalized();
  ASSERT_TRUE(harness.moveVehicle(vehicle));

  octomap::OcTree diff(kResolution);
  obstacle(diff, root, vehicle);
  const Occupied occupied(diff);
  // The vehicle stays a valid place to restart from (up to the field's quantisation).
  ASSERT_GE(occupied.distance(vehicle), kClearance + kQuantisation);
  const auto last_tree = harness.waitForTree(systemNowNs(), 1);
  ASSERT_TRUE(last_tree);
  harness.publishMap(makeUpdate(diff, 2, 1));

  ASSERT_TRUE(harness.spinUntil([&] { return !harness.cancels.empty(); }));
  const msg::WaypointCancel cancel = harness.cancels.front();
  EXPECT_EQ(cancel.query_id(), 1u);
  EXPECT_EQ(cancel.waypoint_id(), first.waypoint_id());
  EXPECT_EQ(cancel.reason(), reason) << cancel.reason_text();
  EXPECT_FALSE(cancel.reason_text().empty());

  // The replanned tree and path start at the vehicle, and the path avoids the obstacle.
  const int64_t cancelled = stampNs(cancel.header()) - 1;
  const auto path = harness.waitForPath(cancelled, 1);
  ASSERT_TRUE(path);
  EXPECT_LT((toVector(path->poses()[0].position()) - vehicle).norm(), 1e-6)
      << "path starts at " << toVector(path->poses()[0].position()).transpose();
  EXPECT_GE(occupied.polyline(pathPositions(*path)), kClearance - kQuantisation);
  const auto tree = harness.waitForTree(cancelled, 1);
  ASSERT_TRUE(tree);
  ASSERT_GE(tree->root_index(), 0);
  EXPECT_LT((toVector(tree->nodes()[tree->root_index()]) - vehicle).norm(), 1e-6);
  EXPECT_GE(tree->iterations(), last_tree->iterations()) << "iterations count the whole query";

  // The next request (the vehicle reached nothing) is answered from there, around it.
  std::vector<Eigen::Vector3d> visited{vehicle};
  ASSERT_TRUE(harness.followToGoal(1, 0, &visited));
  EXPECT_LE((visited[1] - vehicle).norm(), kRange + 1e-6) << "not a child of the new root";
  EXPECT_GT(harness.waypoints[1].waypoint_id(), first.waypoint_id());
  EXPECT_GE(occupied.polyline(visited), kClearance - kQuantisation);
  EXPECT_LE((visited.back() - kGoal).norm(), 1.0);
  EXPECT_EQ(harness.cancels.size(), 1u) << describe(harness.cancels);
  EXPECT_VIEWS_WELL_FORMED(harness);
}

TEST(PlanningComponentTest, CollidingRootCancelsAndReplansFromTheVehicle) {
  forEachPairing(94, [](const Pairing& pairing, int domain) {
    // A column on the root, the vehicle 2.2 m short of it (clear of the column).
    restartScenario(
        pairing, domain, 2.2,
        [](octomap::OcTree& diff, const Eigen::Vector3d& root, const Eigen::Vector3d&) {
          addColumn(diff, root);
        },
        msg::CANCEL_REASON_ROOT_IN_COLLISION);
  });
}

TEST(PlanningComponentTest, BlockedApproachCancelsAndReplansFromTheVehicle) {
  forEachPairing(95, [](const Pairing& pairing, int domain) {
    // The vehicle 3.8 m short of the root (navigation put it behind the start), a column
    // half-way: both ends stay clear, the segment between them does not.
    restartScenario(
        pairing, domain, 3.8,
        [](octomap::OcTree& diff, const Eigen::Vector3d& root, const Eigen::Vector3d& vehicle) {
          addColumn(diff, 0.5 * (root + vehicle));
          const Occupied occupied(diff);
          ASSERT_GE(occupied.distance(root), kClearance + kQuantisation);
          ASSERT_LT(occupied.segment(vehicle, root), kClearance - kQuantisation);
        },
        msg::CANCEL_REASON_APPROACH_IN_COLLISION);
  });
}

// An increment on a version the replica never got is not applied; the planner calls
// map/request_full (served here like the mapping component: a FULL of the current version),
// plans with that map, and applies the increments that follow it without asking again.
TEST(PlanningComponentTest, SequenceGapCallsRequestFullAndRecovers) {
  forEachPairing(96, [](const Pairing& pairing, int domain) {
    PlanningHarness harness(pairing.planner, pairing.handler, domain);
    const octomap::OcTree wall = wallMap();
    const Occupied occupied(wall);
    harness.serveFullMap([&] { harness.publishMap(makeUpdate(wall, 3, 0)); });
    ASSERT_TRUE(harness.waitForPlannerReaders());
    ASSERT_TRUE(harness.publishMapAndWait(makeUpdate(octomap::OcTree(kResolution), 1, 0)));
    ASSERT_TRUE(harness.startQuery(makeQuery(1, kStart, kGoal)));
    ASSERT_TRUE(harness.requestWaypoint(0));
    const msg::Waypoint first = harness.waypoints.back();
    ASSERT_TRUE(harness.moveVehicle(toVector(first.position())));
    EXPECT_TRUE(harness.sequence_at_full_request.empty());

    harness.publishMap(makeUpdate(wall, 3, 2));  // version 2 never came
    ASSERT_TRUE(harness.spinUntil([&] { return harness.planning().mapSequence() == 3; }));
    const int64_t applied = systemNowNs();
    ASSERT_FALSE(harness.sequence_at_full_request.empty()) << "map/request_full not called";
    EXPECT_EQ(harness.sequence_at_full_request.front(), 1u) << "the gapped increment was applied";

    const auto around = harness.waitForPath(applied, 1);
    ASSERT_TRUE(around);
    EXPECT_GE(occupied.polyline(pathPositions(*around)), kClearance - kQuantisation);

    // The chain continues from the FULL version; the calls stop.
    octomap::OcTree column(kResolution);
    addColumn(column, {15.0, 8.0, kDepth});
    ASSERT_TRUE(harness.publishMapAndWait(makeUpdate(column, 4, 3)));
    harness.spinFor(600ms);  // a call in flight at the recovery is served meanwhile
    const std::size_t calls = harness.sequence_at_full_request.size();
    harness.spinFor(600ms);  // three full_request_periods
    EXPECT_EQ(harness.sequence_at_full_request.size(), calls) << "still calling map/request_full";

    std::vector<Eigen::Vector3d> visited{toVector(first.position())};
    ASSERT_TRUE(harness.followToGoal(1, first.waypoint_id(), &visited));
    EXPECT_GE(occupied.polyline(visited), kClearance - kQuantisation);
    EXPECT_LE((visited.back() - kGoal).norm(), 1.0);
    EXPECT_EQ(harness.planning().mapSequence(), 4u);
    EXPECT_TRUE(harness.cancels.empty()) << describe(harness.cancels);
    EXPECT_VIEWS_WELL_FORMED(harness);
  });
}

// A new query cancels the active waypoint of the one it replaces (QUERY_REPLACED) and plans
// from the vehicle; replacing a query with no waypoint out cancels nothing; a request that
// overtakes its query is answered once the query starts, a stale one never.
TEST(PlanningComponentTest, NewQueryCancelsTheActiveWaypointAsReplaced) {
  forEachPairing(97, [](const Pairing& pairing, int domain) {
    PlanningHarness harness(pairing.planner, pairing.handler, domain);
    ASSERT_TRUE(harness.waitForPlannerReaders());
    ASSERT_TRUE(harness.publishMapAndWait(makeUpdate(octomap::OcTree(kResolution), 1, 0)));
    ASSERT_TRUE(harness.startQuery(makeQuery(1, kStart, kGoal)));
    ASSERT_TRUE(harness.requestWaypoint(0));
    const msg::Waypoint first = harness.waypoints.back();
    const Eigen::Vector3d vehicle = toVector(first.position());
    ASSERT_TRUE(harness.moveVehicle(vehicle));

    const int64_t replaced = systemNowNs();
    const Eigen::Vector3d goal2(18.0, 8.0, kDepth);
    harness.publishQuery(makeQuery(2, kStart, goal2));
    ASSERT_TRUE(harness.spinUntil([&] { return !harness.cancels.empty(); }));
    const msg::WaypointCancel cancel = harness.cancels.front();
    EXPECT_EQ(cancel.reason(), msg::CANCEL_REASON_QUERY_REPLACED) << cancel.reason_text();
    EXPECT_EQ(cancel.waypoint_id(), first.waypoint_id());
    EXPECT_EQ(cancel.query_id(), 1u);
    const auto path2 = harness.waitForPath(replaced, 2);
    ASSERT_TRUE(path2);
    EXPECT_LT((toVector(path2->poses()[0].position()) - vehicle).norm(), 1e-6)
        << "query 2 should start at the vehicle, not at its start field";

    // Query 2 has no waypoint out: query 3 replaces it silently. Its first request overtakes
    // it (sent first here; on two topics DDS may deliver them in either order), after a stale
    // one of query 1.
    const Eigen::Vector3d goal3(18.0, -8.0, kDepth);
    harness.sendWaypointRequest(first.waypoint_id(), 1);
    harness.sendWaypointRequest(0, 3);
    harness.spinFor(200ms);  // so that it arrives first (when it does not, the test is weaker)
    harness.publishQuery(makeQuery(3, kStart, goal3));
    ASSERT_TRUE(harness.spinUntil([&] { return harness.waypoints.size() > 1; }))
        << "the request that overtook its query was never answered";
    const msg::Waypoint third = harness.waypoints.back();
    EXPECT_EQ(third.query_id(), 3u);
    EXPECT_GT(third.waypoint_id(), first.waypoint_id());
    EXPECT_LE((toVector(third.position()) - vehicle).norm(), kRange + 1e-6);
    EXPECT_EQ(harness.waypoints.size(), 2u) << "the stale request of query 1 was answered";

    std::vector<Eigen::Vector3d> visited{vehicle, toVector(third.position())};
    harness.vehicle = visited.back();
    ASSERT_TRUE(harness.followToGoal(3, third.waypoint_id(), &visited));
    EXPECT_LE((visited.back() - goal3).norm(), 1.0);
    EXPECT_EQ(harness.cancels.size(), 1u) << describe(harness.cancels);
    EXPECT_VIEWS_WELL_FORMED(harness);
  });
}

/// A map with a closed ring around `centre` (test_maps.h): unreachable, valid goal.
octomap::OcTree ringAround(const Eigen::Vector3d& centre) {
  octomap::OcTree map(kResolution);
  addRing(map, centre, kDepth);
  return map;
}

// An enclosed goal: NO_SOLUTION (for no waypoint) once the time budget is spent, the request
// stays pending; once a map opens the way (the tree was full without a solution by then) it
// is answered. Then, mid-mission, a map that encloses the goal for a moment removes every
// solution of a query older than its budget: the budget starts again there, so no
// NO_SOLUTION when the next map opens the way at once.
TEST(PlanningComponentTest, EnclosedGoalCancelsWithNoSolution) {
  forEachPairing(98, [](const Pairing& pairing, int domain) {
    constexpr double kBudget = 1.0;
    const Eigen::Vector3d goal(15.0, 0.0, kDepth);
    const octomap::OcTree ring = ringAround(goal);
    const octomap::OcTree open(kResolution);
    PlanningHarness harness(pairing.planner, pairing.handler, domain);
    ASSERT_TRUE(harness.waitForPlannerReaders());
    ASSERT_TRUE(harness.publishMapAndWait(makeUpdate(ring, 1, 0)));
    const int64_t sent = systemNowNs();
    harness.publishQuery(makeQuery(1, kStart, goal, kBudget));
    harness.sendWaypointRequest(0, 1);
    ASSERT_TRUE(harness.spinUntil([&] { return !harness.cancels.empty(); }));
    const msg::WaypointCancel cancel = harness.cancels.front();
    EXPECT_EQ(cancel.reason(), msg::CANCEL_REASON_NO_SOLUTION) << cancel.reason_text();
    EXPECT_EQ(cancel.query_id(), 1u);
    EXPECT_EQ(cancel.waypoint_id(), 0u);
    EXPECT_GE(stampNs(cancel.header()) - sent, static_cast<int64_t>(kBudget * 1e9));
    EXPECT_TRUE(harness.waypoints.empty());
    const auto tree = harness.waitForTree(stampNs(cancel.header()), 1);
    ASSERT_TRUE(tree);
    EXPECT_GT(tree->nodes().size(), 100u);
    EXPECT_TRUE(tree->solution_indices().empty());
    EXPECT_EQ(tree->best_solution_index(), -1);
    const auto path = harness.waitForPath(stampNs(cancel.header()), 1, 0);
    ASSERT_TRUE(path);
    EXPECT_TRUE(path->poses().empty());
    EXPECT_TRUE(harness.waypoints.empty());

    // The way opens: the request still pending is answered.
    ASSERT_TRUE(harness.publishMapAndWait(makeUpdate(open, 2, 0)));
    ASSERT_TRUE(harness.spinUntil([&] { return !harness.waypoints.empty(); }))
        << "the pending request was never answered";
    EXPECT_EQ(harness.waypoints.front().query_id(), 1u);
    EXPECT_EQ(harness.cancels.size(), 1u) << describe(harness.cancels);

    // Mid-mission: query 2 (replacing query 1 and its waypoint), a waypoint out, older than
    // its budget; the goal is enclosed for a moment.
    ASSERT_TRUE(harness.startQuery(makeQuery(2, kStart, goal, kBudget)));
    ASSERT_TRUE(harness.requestWaypoint(0, 2));
    const msg::Waypoint first = harness.waypoints.back();
    ASSERT_TRUE(harness.moveVehicle(toVector(first.position())));
    harness.spinFor(std::chrono::milliseconds(static_cast<int>(1000 * kBudget) + 200));
    ASSERT_TRUE(harness.publishMapAndWait(makeUpdate(ring, 3, 0)));
    const int64_t enclosed = systemNowNs();
    ASSERT_TRUE(harness.publishMapAndWait(makeUpdate(open, 4, 0)));
    ASSERT_TRUE(harness.waitForPath(enclosed, 2));
    std::vector<Eigen::Vector3d> visited{toVector(first.position())};
    ASSERT_TRUE(harness.followToGoal(2, first.waypoint_id(), &visited));
    EXPECT_LE((visited.back() - goal).norm(), 1.0);
    for (const auto& c : harness.cancels) {
      EXPECT_NE(c.query_id(), 2u) << describe(harness.cancels);
    }
    ASSERT_EQ(harness.cancels.size(), 2u) << describe(harness.cancels);
    EXPECT_EQ(harness.cancels[1].reason(), msg::CANCEL_REASON_QUERY_REPLACED);
    EXPECT_VIEWS_WELL_FORMED(harness);
  });
}

// planner/tree against planner/path and the waypoints: the same snapshot (same stamp) gives
// the path as the root -> best solution chain; the root is the last waypoint sent; the
// iteration count grows; the tree keeps the clearance; a repeated request gets the active
// waypoint again. (Every tree received in every test also passes checkTree().)
TEST(PlanningComponentTest, TreeMatchesPathAndWaypoints) {
  forEachPairing(99, [](const Pairing& pairing, int domain) {
    PlanningHarness harness(pairing.planner, pairing.handler, domain);
    const octomap::OcTree wall = wallMap();
    const Occupied occupied(wall);
    ASSERT_TRUE(harness.startQuery(wall));

    ASSERT_TRUE(harness.requestWaypoint(0));
    const msg::Waypoint first = harness.waypoints.back();
    const Eigen::Vector3d root = toVector(first.position());
    // Repeated (the vehicle has not reached it): the same waypoint, nothing popped.
    ASSERT_TRUE(harness.requestWaypoint(0));
    EXPECT_EQ(harness.waypoints.back().waypoint_id(), first.waypoint_id());
    EXPECT_LT((toVector(harness.waypoints.back().position()) - root).norm(), 1e-9);

    // A tree and a path of one snapshot (same stamp), taken after the pop; either may arrive
    // first, and best-effort views may be lost.
    const int64_t popped = stampNs(first.header());
    std::optional<msg::PlannerTree> tree;
    std::optional<msg::Path> matched_path;
    ASSERT_TRUE(harness.spinUntil([&] {
      for (const auto& t : harness.trees) {
        if (stampNs(t.header()) <= popped || t.best_solution_index() < 0) continue;
        for (const auto& path : harness.paths) {
          if (stampNs(path.header()) == stampNs(t.header())) {
            tree = t;
            matched_path = path;
            return true;
          }
        }
      }
      return false;
    })) << harness.trees.size()
        << " trees, " << harness.paths.size() << " paths";
    EXPECT_VIEWS_WELL_FORMED(harness);
    ASSERT_GE(tree->root_index(), 0);
    EXPECT_LT((toVector(tree->nodes()[tree->root_index()]) - root).norm(), 1e-9);
    const std::vector<Eigen::Vector3d> chain = bestChain(*tree);
    const std::vector<Eigen::Vector3d> poses = pathPositions(*matched_path);
    ASSERT_EQ(chain.size(), poses.size());
    for (std::size_t i = 0; i < chain.size(); ++i) {
      EXPECT_LT((chain[i] - poses[i]).norm(), 1e-9) << "pose " << i;
    }
    EXPECT_GE(matched_path->cost(), tree->costs()[tree->best_solution_index()] - 1e-9);
    EXPECT_GT(tree->iterations(), 0u);
    for (std::size_t i = 0; i < tree->nodes().size(); ++i) {
      const int32_t parent = tree->parents()[i];
      if (parent < 0) continue;
      EXPECT_GE(occupied.segment(toVector(tree->nodes()[parent]), toVector(tree->nodes()[i])),
                kClearance - kQuantisation)
          << "edge " << parent << " -> " << i;
    }

    // Iterations of query 1 never decrease (they count the whole query).
    uint64_t iterations = 0;
    for (const auto& t : harness.trees) {
      if (t.query_id() != 1) continue;
      EXPECT_GE(t.iterations(), iterations);
      iterations = t.iterations();
    }
    std::vector<Eigen::Vector3d> visited{kStart, root};
    harness.vehicle = root;
    ASSERT_TRUE(harness.followToGoal(1, first.waypoint_id(), &visited));
    EXPECT_GE(occupied.polyline(visited), kClearance - kQuantisation);
    const auto last = harness.waitForTree(stampNs(harness.waypoints.back().header()), 1);
    ASSERT_TRUE(last);
    EXPECT_LT((toVector(last->nodes()[last->root_index()]) - visited.back()).norm(), 1e-9);
    EXPECT_TRUE(harness.cancels.empty()) << describe(harness.cancels);
    EXPECT_VIEWS_WELL_FORMED(harness);
  });
}

TEST(PlanningComponentTest, SamplingSharesAboveOneAreRefusedNamingBoth) {
  interfaces::Node node("planning",
                        interfaces::nodeOptions(Vendor::CYCLONEDDS, 83,
                                                {"goal_bias:=0.5", "narrow_passage_bias:=0.6"}));
  PlanningComponent planning;
  try {
    planning.configure(node);
    FAIL() << "configure() accepted goal_bias 0.5 + narrow_passage_bias 0.6";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("goal_bias + narrow_passage_bias"), std::string::npos)
        << error.what();
  }
}

}  // namespace
}  // namespace auv::planning
