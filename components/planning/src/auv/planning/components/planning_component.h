#pragma once
// The `planning` component: the online anytime RRT* of docs/paper.md §2.2 on DDS. It keeps a
// replica of the occupancy map from `map/update`, grows the tree in its own thread, answers
// `planner/waypoint_request` with `planner/waypoint`, and cancels the active waypoint on
// `planner/cancel` when the map blocks the way to it (Section 2.2.1).

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <future>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include <octomap/OcTree.h>
#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/SpaceInformation.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "auv/interfaces/component.h"
#include "auv/mapping/map_replica.h"
#include "auv/planning/distance_field.h"
#include "auv/planning/map_validity.h"
#include "auv/planning/online_rrt_star.h"
#include "auv/planning/visibility_cost.h"

namespace auv::planning {

class ReplicaDistanceField;

/// Subscribes `map/update` (map), `nav/odometry` (state), `mission/query` and
/// `planner/waypoint_request` (command); publishes `planner/waypoint`, `planner/cancel`
/// (command), `planner/path` and `planner/tree` (viewing); calls `map/request_full` (Trigger)
/// when an increment does not continue the replica's version.
///
/// A waypoint request whose reached_waypoint_id is not the active waypoint (a repeat: the
/// answer was lost or crossed it) gets the active waypoint again instead of the next one; a
/// request may also arrive before the query it names has started.
///
/// Threading: callbacks run on the executor and only queue data (never wait for the planning
/// mutex, which would stall every component composed in the process); the planning thread applies
/// map updates, re-checks the tree and solves in slices of iteration_budget, all under that mutex
/// (the core's rule: no map update while solving).
class PlanningComponent : public interfaces::Component {
 public:
  struct Options {
    double range = 2.0;       ///< m, δ: RRT* extension length, in [0.05, 100].
    double goal_bias = 0.05;  ///< probability of sampling the goal, in [0, 1].
    /// share of the random states drawn by the bridge test (narrow passages), in [0, 1].
    double narrow_passage_bias = 0.1;
    double rewire_factor = 1.1;      ///< RRT* rewiring radius factor, in [1, 10].
    ClearanceOptions clearance;      ///< hull_radius and safety_margin (m).
    double visibility_weight = 1.0;  ///< w of the Eq. (1) term, in [0, 100].
    /// true: plan in the horizontal plane even when a query asks for 3-D, at the query's
    /// start depth (the paper's 2-D profiler setup).
    bool fixed_depth = false;
    /// m, leaf size map updates must have (a replica of another resolution is rejected), in
    /// [0.01, 10]; also the resolution of the empty map used before the first update.
    double map_resolution = 0.5;
    /// m, distances are clamped here (>= 2 d_e keeps Eq. (1) exact), in [0.5, 100].
    double max_distance = 10.0;
    /// m, the distance field covers the query bounds grown by this margin, in [0, 100].
    double field_margin = 5.0;
    double iteration_budget = 0.1;  ///< s, length of one solve() slice, in [0.005, 10].
    /// Growing pauses at this many nodes until popWaypoint() or a restart prunes the tree:
    /// pruning and re-indexing cost O(tree size) while the waypoint request waits. A full
    /// tree without a solution is regrown from its root instead (nothing else would prune
    /// it). In [100, 1e7].
    std::size_t max_tree_size = 20000;
    /// s, time budget when a query gives 0, in [0.1, 3600]. A query is cancelled with
    /// NO_SOLUTION when its tree has had no solution for this long: since the query started,
    /// since a restart, or since an obstacle removed the last solution.
    double default_time_budget = 10.0;
    double path_rate = 2.0;           ///< Hz, rate of planner/path, in [0.01, 100].
    double tree_rate = 1.0;           ///< Hz, rate of planner/tree, in [0.01, 100].
    double waypoint_speed = 0.5;      ///< m/s, Waypoint.speed, in [0.01, 10].
    double waypoint_tolerance = 0.5;  ///< m, Waypoint.tolerance, in [0.01, 10].
    /// s, period of map/request_full calls while the replica misses an update, in [0.1, 60].
    double full_request_period = 1.0;
    std::string map_id = "octomap";     ///< OctomapUpdate.map_id this planner follows.
    std::string world_frame = "world";  ///< frame of the published poses (NED).
  };

  PlanningComponent();
  ~PlanningComponent() override;

  void configure(interfaces::Node& node) override;
  void activate() override;
  void deactivate() override;
  void cleanup() override;

  /// Map version the replica holds (0: none yet). Thread-safe.
  uint64_t mapSequence() const { return map_sequence_; }
  /// Planning slices run since activate(). Thread-safe.
  uint64_t slices() const { return slices_; }
  /// Latest position from `nav/odometry` (none yet: nullopt). Thread-safe.
  std::optional<Eigen::Vector3d> vehiclePosition() const {
    std::lock_guard<std::mutex> lock(inbox_mutex_);
    return vehicle_position_;
  }

 private:
  struct ActiveQuery;  // space, objective, planner and bookkeeping of the current query

  void onMapUpdate(const msg::OctomapUpdate& update);
  void onOdometry(const msg::Odometry& odometry);
  void onQuery(const msg::PlannerQuery& query);
  void onWaypointRequest(const msg::WaypointRequest& request);
  /// Planning thread, under mutex_: answers now, or keeps it pending until a solution exists.
  void handleWaypointRequest(const msg::WaypointRequest& request);
  void planningLoop();
  /// Planning thread, under mutex_: the queued map updates, a queued query, then the queued
  /// waypoint requests.
  void applyMapUpdates();
  void applyMapUpdate(const msg::OctomapUpdate& update);
  void startQuery(const msg::PlannerQuery& query);
  void planSlice();
  /// Under mutex_: answers a pending waypoint request if the tree has a solution.
  void answerWaypointRequest();
  void cancel(uint64_t waypoint_id, int reason, const std::string& text);
  void publishViews();
  void requestFullMapIfNeeded();
  /// Whether the segment stays at least hull_radius from the map (no margin): the test of the
  /// way from the vehicle to the tree root.
  bool hullPassesAlong(const Eigen::Vector3d& from, const Eigen::Vector3d& to) const;
  /// Whether the hull passes from `vehicle` to the tree's `root` the way the controller will
  /// drive: through the waypoint it still heads for, if any (forgotten once within tolerance).
  bool vehicleReachesRoot(ActiveQuery& q, const Eigen::Vector3d& vehicle,
                          const Eigen::Vector3d& root) const;
  /// The vehicle's position as a state of the active query's space (clamped to its bounds).
  void vehicleState(ompl::base::State* state) const;

  interfaces::Node* node_ = nullptr;
  Options options_;
  std::shared_ptr<interfaces::Subscription<msg::OctomapUpdate>> map_sub_;
  std::shared_ptr<interfaces::Subscription<msg::Odometry>> odometry_sub_;
  std::shared_ptr<interfaces::Subscription<msg::PlannerQuery>> query_sub_;
  std::shared_ptr<interfaces::Subscription<msg::WaypointRequest>> request_sub_;
  std::shared_ptr<interfaces::Publisher<msg::Waypoint>> waypoint_pub_;
  std::shared_ptr<interfaces::Publisher<msg::WaypointCancel>> cancel_pub_;
  std::shared_ptr<interfaces::Publisher<msg::Path>> path_pub_;
  std::shared_ptr<interfaces::Publisher<msg::PlannerTree>> tree_pub_;
  std::shared_ptr<interfaces::Client<msg::TriggerRequest, msg::TriggerReply>> full_client_;
  std::shared_ptr<interfaces::Timer> full_request_timer_;

  // Filled by callbacks, drained by the planning thread.
  mutable std::mutex inbox_mutex_;
  std::condition_variable inbox_changed_;
  std::deque<msg::OctomapUpdate> map_inbox_;
  std::optional<msg::PlannerQuery> query_inbox_;
  std::deque<msg::WaypointRequest> request_inbox_;
  std::optional<Eigen::Vector3d> vehicle_position_;  // guarded by inbox_mutex_

  // Planning state: the planning thread and onWaypointRequest, under mutex_.
  std::mutex mutex_;
  std::unique_ptr<mapping::MapReplica> replica_;  // the map from map/update
  std::shared_ptr<ReplicaDistanceField> field_;
  std::unique_ptr<ActiveQuery> query_;
  std::optional<msg::WaypointRequest> pending_request_;  // for the active query
  std::optional<msg::WaypointRequest> early_request_;    // for a query not started (yet)
  uint64_t next_waypoint_id_ = 1;

  // What changed in the map since the tree was last re-checked (planning thread only).
  Eigen::AlignedBox3d changed_region_;
  bool recheck_everything_ = true;  // a FULL map arrived: no box says what changed

  std::atomic<uint64_t> map_sequence_{0};
  std::atomic<bool> full_map_needed_{false};
  std::future<msg::TriggerReply> full_reply_;
  std::atomic<uint64_t> slices_{0};
  std::atomic<bool> running_{false};
  std::thread thread_;
  int64_t last_path_ns_ = 0;
  int64_t last_tree_ns_ = 0;
};

}  // namespace auv::planning
