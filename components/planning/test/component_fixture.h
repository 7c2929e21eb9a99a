// The planning component on real DDS for the component tests: the component on one vendor, a
// test mission handler (map publisher, odometry, queries, waypoint requests, map/request_full
// server) on the other, same domain; geometry checks against the maps the test published; and
// a structural check of every planner/tree and planner/path received.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "auv/interfaces/executor.h"
#include "auv/interfaces/msg_eigen.h"
#include "auv/interfaces/msg_time.h"
#include "auv/planning/components/planning_component.h"
#include "test_maps.h"

namespace auv::planning::testing {

using namespace std::chrono_literals;
using interfaces::Vendor;

constexpr double kDepth = 5.0;
constexpr double kHullRadius = 0.6;
constexpr double kSafetyMargin = 0.4;
constexpr double kClearance = kHullRadius + kSafetyMargin;
constexpr double kRange = 3.0;  // the harness's `range`
// The distance field measures between cell centres: a point may lie up to half a cell
// diagonal closer to an occupied cell than its own cell's centre.
const double kQuantisation = 0.5 * std::sqrt(3.0) * kResolution;
// Wall across the straight line start -> goal (cells with centres x = 10.25, |y| <= 5.75).
const Eigen::Vector3d kWallMin(10.0, -6.0, 0.0);
const Eigen::Vector3d kWallMax(10.5, 6.0, 10.0);
const Eigen::Vector3d kStart(2.0, 0.0, kDepth);
const Eigen::Vector3d kGoal(18.0, 0.0, kDepth);
const Eigen::Vector3d kBoundsMin(0.0, -10.0, 4.0);
const Eigen::Vector3d kBoundsMax(20.0, 10.0, 6.0);

using interfaces::toPoint;
inline Eigen::Vector3d toVector(const msg::Point& p) { return interfaces::toEigen(p); }
inline int64_t stampNs(const msg::Header& header) {
  return interfaces::toNanoseconds(header.stamp());
}
/// The clock the planner stamps with (system time): stamps later than this were made later.
inline int64_t systemNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

/// Occupied cell centres of a map, for brute-force clearance checks.
class Occupied {
 public:
  explicit Occupied(const octomap::OcTree& tree) {
    for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
      if (tree.isNodeOccupied(*it)) centres_.emplace_back(it.getX(), it.getY(), it.getZ());
    }
  }
  bool empty() const { return centres_.empty(); }
  /// Distance from `point` to the nearest occupied cell centre.
  double distance(const Eigen::Vector3d& point) const {
    double nearest = std::numeric_limits<double>::infinity();
    for (const auto& centre : centres_) nearest = std::min(nearest, (centre - point).norm());
    return nearest;
  }
  /// Smallest distance() along the segment, sampled every 0.1 m.
  double segment(const Eigen::Vector3d& from, const Eigen::Vector3d& to) const {
    const int steps = std::max(1, static_cast<int>(std::ceil((to - from).norm() / 0.1)));
    double nearest = std::numeric_limits<double>::infinity();
    for (int i = 0; i <= steps; ++i) {
      nearest = std::min(nearest, distance(from + (to - from) * i / steps));
    }
    return nearest;
  }
  /// Smallest segment() along the polyline.
  double polyline(const std::vector<Eigen::Vector3d>& points) const {
    double nearest =
        points.size() == 1 ? distance(points[0]) : std::numeric_limits<double>::infinity();
    for (std::size_t i = 1; i < points.size(); ++i) {
      nearest = std::min(nearest, segment(points[i - 1], points[i]));
    }
    return nearest;
  }
  /// True when a state there keeps the planner's clearance (up to the field's quantisation).
  bool clear(const Eigen::Vector3d& point) const {
    return distance(point) >= kClearance - kQuantisation;
  }

 private:
  std::vector<Eigen::Vector3d> centres_;
};

/// A map update of `tree` (.ot stream): FULL when base is 0, else INCREMENTAL on base.
inline msg::OctomapUpdate makeUpdate(const octomap::OcTree& tree, uint64_t sequence,
                                     uint64_t base) {
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
  // Every leaf of the stream may have changed: its box, as the mapping component reports it.
  double x0, y0, z0, x1, y1, z1;
  tree.getMetricMin(x0, y0, z0);
  tree.getMetricMax(x1, y1, z1);
  update.changed_min().x(x0);
  update.changed_min().y(y0);
  update.changed_min().z(z0);
  update.changed_max().x(x1);
  update.changed_max().y(y1);
  update.changed_max().z(z1);
  return update;
}

inline octomap::OcTree wallMap() {
  octomap::OcTree map(kResolution);
  addOccupiedBox(map, kWallMin, kWallMax);
  return map;
}

/// One column of cells (z in [kDepth - 1, kDepth + 1]): the cell holding `at` in x and y.
inline void addColumn(octomap::OcTree& map, const Eigen::Vector3d& at) {
  const double x = (std::floor(at.x() / kResolution) + 0.5) * kResolution;
  const double y = (std::floor(at.y() / kResolution) + 0.5) * kResolution;
  const Eigen::Vector2d centre(x, y);
  addOccupiedBox(map, {centre.x() - 0.25, centre.y() - 0.25, kDepth - 1.0},
                 {centre.x() + 0.25, centre.y() + 0.25, kDepth + 1.0});
}

/// A query in the test world (fixed depth, visibility cost) from `start` to `goal`.
inline msg::PlannerQuery makeQuery(uint64_t id, const Eigen::Vector3d& start,
                                   const Eigen::Vector3d& goal, double time_budget = 0.0) {
  msg::PlannerQuery query;
  query.header().frame_id("world");
  query.query_id(id);
  query.start().position(toPoint(start));
  query.start().orientation().w(1.0);
  query.goal().position(toPoint(goal));
  query.goal().orientation().w(1.0);
  query.goal_tolerance(1.0);
  query.time_budget(time_budget);
  query.objective(msg::PLANNER_OBJECTIVE_VISIBILITY_COST);
  query.expected_distance(3.0);
  query.admissible_range(1.0);
  query.bounds_min(toPoint(kBoundsMin));
  query.bounds_max(toPoint(kBoundsMax));
  query.fixed_depth(true);
  query.depth(kDepth);
  return query;
}

/// Empty when `tree` is a well-formed snapshot of a tree for `query`, else what is wrong.
inline std::string checkTree(const msg::PlannerTree& tree, const msg::PlannerQuery& query) {
  std::ostringstream error;
  const auto n = static_cast<int32_t>(tree.nodes().size());
  if (tree.parents().size() != tree.nodes().size() || tree.costs().size() != tree.nodes().size()) {
    error << n << " nodes but " << tree.parents().size() << " parents, " << tree.costs().size()
          << " costs";
    return error.str();
  }
  if (n == 0) {
    if (tree.root_index() != -1 || tree.best_solution_index() != -1 ||
        !tree.solution_indices().empty()) {
      error << "empty tree with root " << tree.root_index() << ", best "
            << tree.best_solution_index() << ", " << tree.solution_indices().size() << " solutions";
    }
    return error.str();
  }
  const int32_t root = tree.root_index();
  if (root < 0 || root >= n || tree.parents()[root] != -1) return "bad root_index";
  if (std::abs(tree.costs()[root]) > 1e-9) return "root cost is not 0";
  const Eigen::Vector3d goal(query.goal().position().x(), query.goal().position().y(),
                             query.depth());
  for (int32_t i = 0; i < n; ++i) {
    const Eigen::Vector3d p = toVector(tree.nodes()[i]);
    if ((p.array() < toVector(query.bounds_min()).array() - 1e-9).any() ||
        (p.array() > toVector(query.bounds_max()).array() + 1e-9).any() ||
        std::abs(p.z() - query.depth()) > 1e-9) {
      error << "node " << i << " at " << p.transpose() << " outside the planning space";
      return error.str();
    }
    if (i == root) continue;
    const int32_t parent = tree.parents()[i];
    if (parent < 0 || parent >= n || parent == i) {
      error << "node " << i << " has parent " << parent;
      return error.str();
    }
    if (tree.costs()[i] < tree.costs()[parent] - 1e-9) {
      error << "node " << i << " is cheaper than its parent";
      return error.str();
    }
    if ((p - toVector(tree.nodes()[parent])).norm() > kRange + 1e-6) {
      error << "edge " << parent << " -> " << i << " longer than range";
      return error.str();
    }
  }
  // Every node reaches the root: no cycles, one tree.
  std::vector<int8_t> reaches(n, 0);  // 0 unknown, 1 yes
  reaches[root] = 1;
  for (int32_t i = 0; i < n; ++i) {
    std::vector<int32_t> chain;
    int32_t at = i;
    while (reaches[at] == 0 && static_cast<int32_t>(chain.size()) <= n) {
      chain.push_back(at);
      at = tree.parents()[at];
    }
    if (reaches[at] == 0) {
      error << "node " << i << " does not reach the root";
      return error.str();
    }
    for (int32_t c : chain) reaches[c] = 1;
  }
  std::vector<bool> seen(n, false);
  for (int32_t s : tree.solution_indices()) {
    if (s < 0 || s >= n || seen[s]) {
      error << "bad or repeated solution index " << s;
      return error.str();
    }
    seen[s] = true;
    if ((toVector(tree.nodes()[s]) - goal).norm() > query.goal_tolerance() + 1e-9) {
      error << "solution " << s << " farther than goal_tolerance from the goal";
      return error.str();
    }
  }
  const int32_t best = tree.best_solution_index();
  if ((best == -1) != tree.solution_indices().empty() || (best != -1 && !seen[best])) {
    error << "best_solution_index " << best << " not among " << tree.solution_indices().size()
          << " solution_indices";
    return error.str();
  }
  // Each sampling iteration adds at most one node; the root comes without one.
  if (tree.iterations() + 1 < static_cast<uint64_t>(n)) {
    error << n << " nodes after only " << tree.iterations() << " iterations";
    return error.str();
  }
  return {};
}

/// The planning component and a test mission handler on two nodes, one executor.
class PlanningHarness {
 public:
  /// `start_planner` false: only the handler exists until startPlanner() (a late joiner).
  PlanningHarness(Vendor planner_vendor, Vendor handler_vendor, int domain,
                  bool start_planner = true, std::vector<std::string> overrides = {})
      : planner_vendor_(planner_vendor),
        domain_(domain),
        overrides_(std::move(overrides)),
        handler_node_("mission", interfaces::nodeOptions(handler_vendor, domain)) {
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
        std::function<void(const msg::Path&)>([this](const msg::Path& p) { onPath(p); }));
    tree_sub_ = handler_node_.createSubscription<msg::PlannerTree>(
        "planner/tree", interfaces::viewingQos(),
        std::function<void(const msg::PlannerTree&)>(
            [this](const msg::PlannerTree& t) { onTree(t); }));
    odometry_timer_ = handler_node_.createTimer(0.05, [this] { publishOdometry(); });
    executor_.add(handler_node_);
    if (start_planner) startPlanner();
  }
  ~PlanningHarness() {
    if (planning_) {
      planning_->deactivate();
      planning_->cleanup();
    }
  }

  void startPlanner() {
    std::vector<std::string> overrides = {"map_resolution:=0.5",    "hull_radius:=0.6",
                                          "safety_margin:=0.4",     "range:=3.0",
                                          "iteration_budget:=0.05", "path_rate:=10.0",
                                          "tree_rate:=10.0",        "max_distance:=8.0",
                                          "max_tree_size:=3000",    "full_request_period:=0.2"};
    overrides.insert(overrides.end(), overrides_.begin(), overrides_.end());
    planner_node_ = std::make_unique<interfaces::Node>(
        "planning", interfaces::nodeOptions(planner_vendor_, domain_, overrides));
    planning_ = std::make_unique<PlanningComponent>();
    planning_->configure(*planner_node_);
    executor_.add(*planner_node_);
    planning_->activate();
  }
  PlanningComponent& planning() { return *planning_; }

  bool spinUntil(const std::function<bool()>& done, std::chrono::seconds timeout = 30s) {
    return executor_.spinUntil(done, timeout);
  }
  /// Spins for `duration` (lets time pass; never a pass/fail condition by itself).
  void spinFor(std::chrono::milliseconds duration) {
    const auto end = std::chrono::steady_clock::now() + duration;
    executor_.spinUntil([&] { return std::chrono::steady_clock::now() >= end; }, duration + 1s);
  }

  void publishMap(const msg::OctomapUpdate& update) { map_pub_->publish(update); }
  /// Publishes and waits until the replica holds `update`'s version. One update in flight at
  /// a time: the writer keeps only the newest sample (keep last 1).
  bool publishMapAndWait(const msg::OctomapUpdate& update) {
    publishMap(update);
    return spinUntil([&] { return planning_->mapSequence() == update.sequence_number(); });
  }

  /// Waits until the planner's readers of the handler's topics are matched.
  bool waitForPlannerReaders() {
    return spinUntil([&] {
      return query_pub_->matchedSubscriptions() > 0 && request_pub_->matchedSubscriptions() > 0 &&
             odometry_pub_->matchedSubscriptions() > 0 && map_pub_->matchedSubscriptions() > 0;
    });
  }

  void publishQuery(const msg::PlannerQuery& query) {
    queries_[query.query_id()] = query;
    query_pub_->publish(query);
  }
  /// Publishes `query` and waits for a path of it with a solution (>= 2 poses); a path also
  /// shows that the planner's writers have discovered this node's readers.
  bool startQuery(const msg::PlannerQuery& query) {
    if (!waitForPlannerReaders()) return false;
    const int64_t sent = systemNowNs();
    publishQuery(query);
    return waitForPath(sent, query.query_id()).has_value();
  }
  /// The original harness's sequence: FULL `map` as version 1, then query 1 kStart -> kGoal.
  bool startQuery(const octomap::OcTree& map) {
    if (!waitForPlannerReaders()) return false;
    if (!publishMapAndWait(makeUpdate(map, 1, 0))) return false;
    return startQuery(makeQuery(1, kStart, kGoal));
  }

  /// The first path of `query_id` stamped after `after_ns` with at least `min_poses` poses,
  /// waiting for it; nullopt on timeout.
  std::optional<msg::Path> waitForPath(int64_t after_ns, uint64_t query_id,
                                       std::size_t min_poses = 2) {
    return waitFor<msg::Path>(paths, after_ns, query_id, [&](const msg::Path& path) {
      return path.poses().size() >= min_poses;
    });
  }
  /// The first tree of `query_id` stamped after `after_ns` that satisfies `accept`.
  std::optional<msg::PlannerTree> waitForTree(
      int64_t after_ns, uint64_t query_id,
      const std::function<bool(const msg::PlannerTree&)>& accept = nullptr) {
    return waitFor<msg::PlannerTree>(trees, after_ns, query_id, accept);
  }

  void sendWaypointRequest(uint64_t reached_waypoint_id, uint64_t query_id = 1) {
    msg::WaypointRequest request;
    request.query_id(query_id);
    request.reached_waypoint_id(reached_waypoint_id);
    request_pub_->publish(request);
  }
  /// Asks for the next waypoint; true when it arrived.
  bool requestWaypoint(uint64_t reached_waypoint_id, uint64_t query_id = 1) {
    const std::size_t before = waypoints.size();
    sendWaypointRequest(reached_waypoint_id, query_id);
    return spinUntil([&] { return waypoints.size() > before; });
  }
  /// Moves the simulated vehicle (odometry now and every 50 ms) and waits until the planner
  /// has heard of it.
  bool moveVehicle(const Eigen::Vector3d& position) {
    vehicle = position;
    publishOdometry();
    return spinUntil([&] {
      const auto heard = planning_->vehiclePosition();
      return heard && (*heard - position).norm() < 1e-9;
    });
  }
  /// Follows waypoints of `query_id` as the vehicle (odometry at each one reached) until the
  /// final one; `visited` gets each waypoint's position.
  ::testing::AssertionResult followToGoal(uint64_t query_id, uint64_t reached,
                                          std::vector<Eigen::Vector3d>* visited) {
    for (int i = 0; i < 40; ++i) {
      if (!requestWaypoint(reached, query_id)) {
        return ::testing::AssertionFailure() << "no answer to request " << i + 1;
      }
      const msg::Waypoint& waypoint = waypoints.back();
      if (waypoint.query_id() != query_id || waypoint.waypoint_id() <= reached) {
        return ::testing::AssertionFailure()
               << "waypoint " << waypoint.waypoint_id() << " of query " << waypoint.query_id();
      }
      visited->push_back(toVector(waypoint.position()));
      reached = waypoint.waypoint_id();
      vehicle = visited->back();  // the vehicle reaches it
      publishOdometry();
      if (waypoint.is_final()) return ::testing::AssertionSuccess();
    }
    return ::testing::AssertionFailure() << "no final waypoint after 40";
  }

  /// Serves map/request_full: counts calls, records the replica's version at each call and
  /// runs `on_request` (typically publishing a FULL map).
  void serveFullMap(std::function<void()> on_request) {
    on_full_request_ = std::move(on_request);
    full_service_ = handler_node_.createService<msg::TriggerRequest, msg::TriggerReply>(
        "map/request_full", [this](const msg::TriggerRequest&, msg::TriggerReply& reply) {
          sequence_at_full_request.push_back(planning_ ? planning_->mapSequence() : 0);
          if (on_full_request_) on_full_request_();
          reply.message("full map on the way");
        });
  }

  Eigen::Vector3d vehicle = kStart;
  std::vector<msg::Waypoint> waypoints;
  std::vector<msg::WaypointCancel> cancels;
  std::vector<msg::Path> paths;
  std::vector<msg::PlannerTree> trees;
  std::vector<uint64_t> sequence_at_full_request;
  /// What checkTree() and the path check found wrong in the views received (empty: all fine).
  std::vector<std::string> view_errors;

 private:
  // Copies: the vectors grow while the caller looks at the result.
  template <class T>
  std::optional<T> waitFor(const std::vector<T>& received, int64_t after_ns, uint64_t query_id,
                           const std::function<bool(const T&)>& accept) {
    std::optional<T> found;
    std::size_t checked = 0;
    spinUntil([&] {
      for (; checked < received.size(); ++checked) {
        const T& message = received[checked];
        if (message.query_id() == query_id && stampNs(message.header()) > after_ns &&
            (!accept || accept(message))) {
          found = message;
          return true;
        }
      }
      return false;
    });
    return found;
  }
  void publishOdometry() {
    msg::Odometry odometry;
    odometry.header().frame_id("world");
    odometry.pose().pose().position(toPoint(vehicle));
    odometry.pose().pose().orientation().w(1.0);
    odometry_pub_->publish(odometry);
  }
  void onPath(const msg::Path& path) {
    auto query = queries_.find(path.query_id());
    if (query == queries_.end()) {
      view_errors.push_back("path of unknown query " + std::to_string(path.query_id()));
    } else if (!path.poses().empty()) {
      const msg::PlannerQuery& q = query->second;
      const Eigen::Vector3d goal(q.goal().position().x(), q.goal().position().y(), q.depth());
      if ((toVector(path.poses().back().position()) - goal).norm() > q.goal_tolerance() + 1e-9) {
        view_errors.push_back("path does not end within goal_tolerance");
      }
    }
    paths.push_back(path);
  }
  void onTree(const msg::PlannerTree& tree) {
    auto query = queries_.find(tree.query_id());
    const std::string error = query == queries_.end()
                                  ? "tree of unknown query " + std::to_string(tree.query_id())
                                  : checkTree(tree, query->second);
    if (!error.empty()) view_errors.push_back(error);
    trees.push_back(tree);
  }

  Vendor planner_vendor_;
  int domain_;
  std::vector<std::string> overrides_;
  interfaces::Node handler_node_;
  std::unique_ptr<interfaces::Node> planner_node_;
  std::unique_ptr<PlanningComponent> planning_;
  interfaces::Executor executor_;
  std::map<uint64_t, msg::PlannerQuery> queries_;
  std::function<void()> on_full_request_;
  std::shared_ptr<interfaces::Service<msg::TriggerRequest, msg::TriggerReply>> full_service_;
  std::shared_ptr<interfaces::Publisher<msg::OctomapUpdate>> map_pub_;
  std::shared_ptr<interfaces::Publisher<msg::Odometry>> odometry_pub_;
  std::shared_ptr<interfaces::Publisher<msg::PlannerQuery>> query_pub_;
  std::shared_ptr<interfaces::Publisher<msg::WaypointRequest>> request_pub_;
  std::shared_ptr<interfaces::Subscription<msg::Waypoint>> waypoint_sub_;
  std::shared_ptr<interfaces::Subscription<msg::WaypointCancel>> cancel_sub_;
  std::shared_ptr<interfaces::Subscription<msg::Path>> path_sub_;
  std::shared_ptr<interfaces::Subscription<msg::PlannerTree>> tree_sub_;
  std::shared_ptr<interfaces::Timer> odometry_timer_;
};

/// The chain root -> best solution of `tree` as positions (empty without a solution).
inline std::vector<Eigen::Vector3d> bestChain(const msg::PlannerTree& tree) {
  std::vector<Eigen::Vector3d> chain;
  for (int32_t i = tree.best_solution_index(); i >= 0 && chain.size() <= tree.nodes().size();
       i = tree.parents()[i]) {
    chain.push_back(toVector(tree.nodes()[i]));
  }
  std::reverse(chain.begin(), chain.end());
  return chain;
}

inline std::vector<Eigen::Vector3d> pathPositions(const msg::Path& path) {
  std::vector<Eigen::Vector3d> positions;
  for (const auto& pose : path.poses()) positions.push_back(toVector(pose.position()));
  return positions;
}

/// Both vendor pairings (planner, mission handler), run one after the other on a test's domain.
struct Pairing {
  Vendor planner;
  Vendor handler;
};
inline const std::vector<Pairing>& pairings() {
  static const std::vector<Pairing> all = {{Vendor::CYCLONEDDS, Vendor::FASTDDS},
                                           {Vendor::FASTDDS, Vendor::CYCLONEDDS}};
  return all;
}
inline std::string describe(const Pairing& pairing) {
  return "planner on " + interfaces::toString(pairing.planner) + ", handler on " +
         interfaces::toString(pairing.handler);
}

}  // namespace auv::planning::testing
