// The planning component on real DDS, the component and the test's mission handler on
// different vendors: a FULL map with a wall, odometry and a query across the wall give
// waypoints that reach the goal and keep the clearance; an increment that blocks the way to
// the active waypoint cancels it. Each test on its own domain id (90..99).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <vector>

#include "auv/interfaces/executor.h"
#include "auv/planning/components/planning_component.h"
#include "test_maps.h"

namespace auv::planning {
namespace {

using namespace std::chrono_literals;
using interfaces::Node;
using interfaces::nodeOptions;
using interfaces::Vendor;

constexpr double kDepth = 5.0;
constexpr double kHullRadius = 0.6;
constexpr double kSafetyMargin = 0.4;
constexpr double kClearance = kHullRadius + kSafetyMargin;
// The distance field measures between cell centres: a point may lie up to half a cell
// diagonal closer to an occupied cell than its own cell's centre.
const double kQuantisation = 0.5 * std::sqrt(3.0) * testing::kResolution;
// Wall across the straight line start -> goal (cells with centres x = 10.25, |y| <= 5.75).
const Eigen::Vector3d kWallMin(10.0, -6.0, 0.0);
const Eigen::Vector3d kWallMax(10.5, 6.0, 10.0);
const Eigen::Vector3d kStart(2.0, 0.0, kDepth);
const Eigen::Vector3d kGoal(18.0, 0.0, kDepth);

msg::Point toPoint(const Eigen::Vector3d& v) {
  msg::Point p;
  p.x(v.x());
  p.y(v.y());
  p.z(v.z());
  return p;
}
Eigen::Vector3d toVector(const msg::Point& p) { return {p.x(), p.y(), p.z()}; }

/// Distance from `point` to the nearest occupied cell centre of `tree`.
double distanceToOccupied(const octomap::OcTree& tree, const Eigen::Vector3d& point) {
  double nearest = std::numeric_limits<double>::infinity();
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    const Eigen::Vector3d centre(it.getX(), it.getY(), it.getZ());
    nearest = std::min(nearest, (centre - point).norm());
  }
  return nearest;
}

/// Smallest distanceToOccupied along the segment, sampled every 0.1 m.
double segmentClearance(const octomap::OcTree& tree, const Eigen::Vector3d& from,
                        const Eigen::Vector3d& to) {
  const int steps = std::max(1, static_cast<int>(std::ceil((to - from).norm() / 0.1)));
  double nearest = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= steps; ++i) {
    nearest = std::min(nearest, distanceToOccupied(tree, from + (to - from) * i / steps));
  }
  return nearest;
}

msg::OctomapUpdate makeUpdate(const octomap::OcTree& tree, uint64_t sequence, uint64_t base) {
  std::ostringstream stream;
  tree.write(stream);  // .ot: with log-odds, what applyDiff and the FULL reader expect
  const std::string data = stream.str();
  msg::OctomapUpdate update;
  update.header().frame_id("world");
  update.map_id("octomap");
  update.sequence_number(sequence);
  update.base_sequence(base);
  update.kind(base == 0 ? msg::OCTOMAP_UPDATE_FULL : msg::OCTOMAP_UPDATE_INCREMENTAL);
  update.encoding(msg::OCTOMAP_ENCODING_FULL);
  update.tree_type(tree.getTreeType());
  update.resolution(tree.getResolution());
  update.data(std::vector<uint8_t>(data.begin(), data.end()));
  return update;
}

/// The planning component on one vendor and a mission handler on the other, same domain.
class PlanningHarness {
 public:
  PlanningHarness(Vendor planner_vendor, Vendor handler_vendor, int domain)
      : planner_node_("planning",
                      nodeOptions(planner_vendor, domain,
                                  {"map_resolution:=0.5", "hull_radius:=0.6", "safety_margin:=0.4",
                                   "range:=3.0", "iteration_budget:=0.05", "path_rate:=10.0",
                                   "max_distance:=8.0", "max_tree_size:=3000"})),
        handler_node_("mission", nodeOptions(handler_vendor, domain)) {
    planning_.configure(planner_node_);
    map_pub_ =
        handler_node_.createPublisher<msg::OctomapUpdate>("map/update", interfaces::mapQos());
    odometry_pub_ =
        handler_node_.createPublisher<msg::Odometry>("nav/odometry", interfaces::stateQos());
    query_pub_ =
        handler_node_.createPublisher<msg::PlannerQuery>("mission/query", interfaces::commandQos());
    request_pub_ = handler_node_.createPublisher<msg::WaypointRequest>("planner/waypoint_request",
                                                                       interfaces::commandQos());
    waypoint_sub_ = handler_node_.createSubscription<msg::Waypoint>(
        "planner/waypoint", interfaces::commandQos(),
        std::function<void(const msg::Waypoint&)>(
            [this](const msg::Waypoint& w) { waypoints.push_back(w); }));
    cancel_sub_ = handler_node_.createSubscription<msg::WaypointCancel>(
        "planner/cancel", interfaces::commandQos(),
        std::function<void(const msg::WaypointCancel&)>(
            [this](const msg::WaypointCancel& c) { cancels.push_back(c); }));
    path_sub_ = handler_node_.createSubscription<msg::Path>(
        "planner/path", interfaces::viewingQos(),
        std::function<void(const msg::Path&)>([this](const msg::Path& p) { last_path = p; }));
    odometry_timer_ = handler_node_.createTimer(0.05, [this] { publishOdometry(); });
    executor_.add(planner_node_);
    executor_.add(handler_node_);
    planning_.activate();
  }
  ~PlanningHarness() {
    planning_.deactivate();
    planning_.cleanup();
  }

  bool spinUntil(const std::function<bool()>& done, std::chrono::seconds timeout = 30s) {
    return executor_.spinUntil(done, timeout);
  }

  /// Sends the map, then the query across the wall once the planner can hear it; true when the
  /// planner has a solution (a path with at least two poses).
  bool startQuery(const octomap::OcTree& map) {
    map_pub_->publish(makeUpdate(map, 1, 0));
    if (!spinUntil([&] { return planning_.mapSequence() == 1; })) return false;
    if (!spinUntil([&] {
          return query_pub_->matchedSubscriptions() > 0 && request_pub_->matchedSubscriptions() > 0;
        })) {
      return false;
    }
    msg::PlannerQuery query;
    query.header().frame_id("world");
    query.query_id(1);
    query.start().position(toPoint(kStart));
    query.start().orientation().w(1.0);
    query.goal().position(toPoint(kGoal));
    query.goal().orientation().w(1.0);
    query.goal_tolerance(1.0);
    query.objective(msg::PLANNER_OBJECTIVE_VISIBILITY_COST);
    query.expected_distance(3.0);
    query.admissible_range(1.0);
    query.bounds_min(toPoint({0.0, -10.0, 4.0}));
    query.bounds_max(toPoint({20.0, 10.0, 6.0}));
    query.fixed_depth(true);
    query.depth(kDepth);
    query_pub_->publish(query);
    // A path also shows that the planner's writers have discovered this node's readers.
    return spinUntil([&] { return last_path && last_path->poses().size() >= 2; });
  }

  /// Asks for the next waypoint; true when it arrived.
  bool requestWaypoint(uint64_t reached_waypoint_id) {
    const std::size_t before = waypoints.size();
    msg::WaypointRequest request;
    request.query_id(1);
    request.reached_waypoint_id(reached_waypoint_id);
    request_pub_->publish(request);
    return spinUntil([&] { return waypoints.size() > before; });
  }

  void publishMap(const msg::OctomapUpdate& update) { map_pub_->publish(update); }

  Eigen::Vector3d vehicle = kStart;
  std::vector<msg::Waypoint> waypoints;
  std::vector<msg::WaypointCancel> cancels;
  std::optional<msg::Path> last_path;

 private:
  void publishOdometry() {
    msg::Odometry odometry;
    odometry.header().frame_id("world");
    odometry.pose().pose().position(toPoint(vehicle));
    odometry.pose().pose().orientation().w(1.0);
    odometry_pub_->publish(odometry);
  }

  Node planner_node_;
  Node handler_node_;
  PlanningComponent planning_;
  interfaces::Executor executor_;
  std::shared_ptr<interfaces::Publisher<msg::OctomapUpdate>> map_pub_;
  std::shared_ptr<interfaces::Publisher<msg::Odometry>> odometry_pub_;
  std::shared_ptr<interfaces::Publisher<msg::PlannerQuery>> query_pub_;
  std::shared_ptr<interfaces::Publisher<msg::WaypointRequest>> request_pub_;
  std::shared_ptr<interfaces::Subscription<msg::Waypoint>> waypoint_sub_;
  std::shared_ptr<interfaces::Subscription<msg::WaypointCancel>> cancel_sub_;
  std::shared_ptr<interfaces::Subscription<msg::Path>> path_sub_;
  std::shared_ptr<interfaces::Timer> odometry_timer_;
};

octomap::OcTree wallMap() {
  octomap::OcTree map(testing::kResolution);
  testing::addOccupiedBox(map, kWallMin, kWallMax);
  return map;
}

TEST(PlanningComponentTest, WaypointsCrossTheWallKeepingTheClearance) {
  PlanningHarness harness(Vendor::CYCLONEDDS, Vendor::FASTDDS, 90);
  const octomap::OcTree map = wallMap();
  ASSERT_TRUE(harness.startQuery(map));

  uint64_t reached = 0;
  Eigen::Vector3d previous = kStart;
  for (int i = 0; i < 40; ++i) {
    ASSERT_TRUE(harness.requestWaypoint(reached)) << "no waypoint " << i + 1;
    const msg::Waypoint& waypoint = harness.waypoints.back();
    const Eigen::Vector3d position = toVector(waypoint.position());
    EXPECT_EQ(waypoint.query_id(), 1u);
    EXPECT_GT(waypoint.waypoint_id(), reached);
    EXPECT_NEAR(position.z(), kDepth, 1e-9);
    EXPECT_GE(distanceToOccupied(map, position), kClearance - kQuantisation)
        << "waypoint " << waypoint.waypoint_id() << " at " << position.transpose();
    EXPECT_GE(segmentClearance(map, previous, position), kClearance - kQuantisation)
        << "segment to waypoint " << waypoint.waypoint_id();
    previous = position;
    harness.vehicle = position;  // the vehicle reaches it
    reached = waypoint.waypoint_id();
    if (waypoint.is_final()) break;
  }
  ASSERT_TRUE(harness.waypoints.back().is_final()) << harness.waypoints.size() << " waypoints";
  EXPECT_LE((previous - kGoal).norm(), 1.0);
  EXPECT_GE(harness.waypoints.size(), 2u);  // the wall is in the way of a single hop
  EXPECT_TRUE(harness.cancels.empty()) << harness.cancels.front().reason_text();
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
  octomap::OcTree diff(testing::kResolution);
  testing::addOccupiedBox(diff, obstacle - Eigen::Vector3d(0.25, 0.25, 1.0),
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

}  // namespace
}  // namespace auv::planning
