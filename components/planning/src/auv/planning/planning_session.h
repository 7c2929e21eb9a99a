#pragma once
// The planner's query and waypoint protocol (the paper's §2.2.1), without DDS: one query at a
// time grown by a WaypointPlanner (OnlineRRTstar; ScratchPlanner, the baseline) in slices,
// waypoint requests answered by popping the tree, cancels when the map blocks the way to the
// active waypoint, NO_SOLUTION once a query has had no solution for its time budget. The `planning`
// component wires it to topics and runs it in its planning thread; tests drive it directly with a
// clock of their own.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "auv/config/option_table.h"
#include "auv/planning/distance_field.h"
#include "auv/planning/map_validity.h"
#include "auv/planning/waypoint_planner.h"

namespace octomap {
class OcTree;
}

namespace auv::planning {

class ReplicaDistanceField;

/// Ranges, meaning and units: table() (planning_session.cc).
struct SessionOptions {
  double range = 2.0;       ///< m, δ: RRT* extension length.
  double goal_bias = 0.05;  ///< probability of sampling the goal.
  /// share of the random states drawn by the bridge test (narrow passages).
  double narrow_passage_bias = 0.1;
  double rewire_factor = 1.1;      ///< RRT* rewiring radius factor.
  ClearanceOptions clearance;      ///< hull_radius and safety_margin (m).
  double visibility_weight = 1.0;  ///< w of the Eq. (1) term.
  /// true: plan in the horizontal plane even when a query asks for 3-D, at the query's
  /// start depth (the paper's 2-D profiler setup).
  bool fixed_depth = false;
  /// m, leaf size of the map (the component rejects map updates of another resolution and
  /// starts from an empty map of it); also sets the vehicle -> root check step.
  double map_resolution = 0.5;
  /// m, distances are clamped here (>= 2 d_e keeps Eq. (1) exact).
  double max_distance = 10.0;
  /// m, the distance field covers the query bounds grown by this margin.
  double field_margin = 5.0;
  double iteration_budget = 0.1;  ///< s, length of one planSlice() growth.
  /// Growing pauses at this many nodes until popWaypoint() or a restart prunes the tree:
  /// pruning and re-indexing cost O(tree size) while the waypoint request waits. A full
  /// tree without a solution is regrown from its root instead (nothing else would prune
  /// it).
  std::size_t max_tree_size = 20000;
  /// s, time budget when a query gives 0. A query is cancelled with
  /// NO_SOLUTION when its tree has had no solution for this long: since the query started,
  /// since a restart, or since an obstacle removed the last solution.
  double default_time_budget = 10.0;
  double waypoint_speed = 0.5;      ///< m/s, Waypoint speed.
  double waypoint_tolerance = 0.5;  ///< m, Waypoint tolerance.
  /// "repair": the paper's tree repair (OnlineRRTstar); "scratch" and "restart": the
  /// from-scratch baselines (ScratchPlanner: OMPL's RRTstar, or OnlineRRTstar without the
  /// reuse, planned anew on every map change).
  std::string replanning = "repair";
  /// s: when a map change makes the best path's cost jump above detour_factor × what it was,
  /// the next waypoint waits up to this long for the tree to find a way back under that
  /// factor before the vehicle takes the detour (0: never wait). The vehicle holds at the
  /// waypoint it reached meanwhile.
  double detour_hold = 0.0;
  double detour_factor = 1.5;  ///< the cost ratio that starts a detour_hold

  /// The fields with meaning, unit and range (the planning component's parameters of those
  /// names); the clearance's are in ClearanceOptions::table().
  static const config::OptionTable<SessionOptions>& table();
  /// Throws PlanningConfigError: a range of table(), the clearance's check,
  /// goal_bias + narrow_passage_bias <= 1.
  void check() const;
};

enum class PlanningObjective {
  VISIBILITY_COST,  ///< Eq. (1) along the path (also the planner's default)
  PATH_LENGTH,
};

/// What the mission handler asks for (NED, metres).
struct PlanningQuery {
  uint64_t query_id = 0;  ///< 0 is refused
  /// Where the tree starts when the vehicle's position is unknown.
  Eigen::Vector3d start = Eigen::Vector3d::Zero();
  Eigen::Vector3d goal = Eigen::Vector3d::Zero();
  double goal_tolerance = 0.0;  ///< m, must be > 0
  double time_budget = 0.0;     ///< s, 0: SessionOptions::default_time_budget
  PlanningObjective objective = PlanningObjective::VISIBILITY_COST;
  double expected_distance = 0.0;  ///< m, d_e of Eq. (1)
  double admissible_range = 0.0;   ///< m, Δd_a of Eq. (1)
  Eigen::Vector3d bounds_min = Eigen::Vector3d::Zero();
  Eigen::Vector3d bounds_max = Eigen::Vector3d::Zero();
  std::optional<double> fixed_depth;  ///< m, plan in the horizontal plane at this depth
  /// m, depth band of 3-D planning (z positive down): the space's z-range is the bounds'
  /// intersected with [min_depth, max_depth]. Both 0: no band; any other max_depth <=
  /// min_depth is refused. Ignored in 2-D (fixed_depth here or in SessionOptions).
  double min_depth = 0.0;
  double max_depth = 0.0;
  /// m, water kept between the clearance sphere and known seabed below (ClearanceOptions).
  double min_altitude = 0.0;
  bool hasBand() const { return min_depth != 0.0 || max_depth != 0.0; }
};

struct WaypointRequest {
  uint64_t query_id = 0;
  /// The waypoint the vehicle reached (0: none yet, or none since a cancel).
  uint64_t reached_waypoint_id = 0;
};

struct PlannedWaypoint {
  uint64_t waypoint_id = 0;
  uint64_t query_id = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double heading = 0.0;  ///< rad, of the edge from the previous root
  double speed = 0.0;
  double tolerance = 0.0;
  bool is_final = false;  ///< within the goal tolerance of the goal
  /// The active waypoint again, for a repeated request (its answer was lost or crossed it).
  bool repeat = false;
};

enum class CancelReason {
  ROOT_IN_COLLISION,
  APPROACH_IN_COLLISION,
  QUERY_REPLACED,
  NO_SOLUTION,
  PLANNER_ERROR,
  /// A request for a query this planner never received (it restarted, or the query was lost):
  /// the mission handler re-issues the query.
  UNKNOWN_QUERY,
};

struct WaypointCancel {
  uint64_t waypoint_id = 0;  ///< 0: no waypoint (the query itself)
  uint64_t query_id = 0;
  CancelReason reason = CancelReason::PLANNER_ERROR;
  std::string text;
};

struct PathSnapshot {
  std::vector<Eigen::Vector3d> positions;  ///< root to best solution (empty without one)
  double cost = 0.0;                       ///< infinite without a solution
};

/// Whether a hull of `hull_radius` passes along the segment (sampled every `step` m) without
/// touching the map: the vehicle -> root test, which leaves the safety margin to tracking
/// error. A start already inside the hull radius may move away: the distance must not shrink
/// until it is clear, as in MapMotionValidator's escapes.
bool hullPassesAlong(const DistanceField& field, const Eigen::Vector3d& from,
                     const Eigen::Vector3d& to, double hull_radius, double step);

/// Not thread-safe: the caller serialises every call (the core's rule: no map change while
/// the tree grows). Map changes reach it through onFullMap() and onMapIncrement(), after the
/// caller has applied them to its map.
class PlanningSession {
 public:
  /// What the caller must send, in order; warnings are for its log.
  struct Outbox {
    std::vector<std::variant<PlannedWaypoint, WaypointCancel>> messages;
    std::vector<std::string> warnings;
  };

  /// Throws PlanningConfigError when `options` fail their check().
  explicit PlanningSession(const SessionOptions& options);
  ~PlanningSession();
  PlanningSession(const PlanningSession&) = delete;
  PlanningSession& operator=(const PlanningSession&) = delete;

  /// `map` (which the caller keeps alive) replaced the map as version `version`.
  void onFullMap(octomap::OcTree& map, uint64_t version);
  /// The map changed in place to version `version`, inside [changed_min, changed_max] (a flat
  /// box: unknown where; an empty one: nothing changed).
  void onMapIncrement(const Eigen::Vector3d& changed_min, const Eigen::Vector3d& changed_max,
                      uint64_t version);

  /// Replaces the active query (its active waypoint is cancelled as QUERY_REPLACED) with
  /// `query` on `map`, rooted at the vehicle when its position is known. False when the query
  /// is refused (cancelled as PLANNER_ERROR; no query is active then).
  bool startQuery(const PlanningQuery& query, octomap::OcTree& map,
                  const std::optional<Eigen::Vector3d>& vehicle, double now);
  /// Answers now (a repeat gets the active waypoint again) or keeps the request until the tree
  /// has a solution; a request for a query not started yet is kept for that query. A request
  /// for a newer query that cannot be in flight is cancelled as UNKNOWN_QUERY: one that
  /// reached a waypoint (that query was planned, by a planner before a restart), or a first
  /// request repeated kLostQueryAfter s (node time `now`) after it was kept.
  void onWaypointRequest(const WaypointRequest& request, double now);
  /// s: a query whose first request came this long ago without the query is lost. A request
  /// overtakes its query by milliseconds; mission handlers repeat requests every few seconds.
  static constexpr double kLostQueryAfter = 1.0;

  /// First half of a planning slice: re-checks the tree if the map changed (a blocked root or
  /// way to it cancels the active waypoint and restarts the tree at the vehicle, its budget
  /// from `now`), then grows it for iteration_budget seconds of wall time unless it is full.
  /// True when it grew.
  bool planSlice(const std::optional<Eigen::Vector3d>& vehicle, double now);
  /// Second half, `now` read after the growth: answers the pending request once a solution
  /// exists; cancels with NO_SOLUTION (once) when there has been none for the time budget.
  void finishSlice(double now);

  Outbox takeOutbox();

  bool hasQuery() const { return query_ != nullptr; }
  /// The active query's id (0: none).
  uint64_t queryId() const;
  /// The active waypoint's id (0: none issued since the query's start or the last restart).
  uint64_t activeWaypointId() const;
  /// Whether planSlice() would grow the tree: the caller should not wait for input.
  bool growing() const;
  /// The active query's planner (nullptr: none).
  const WaypointPlanner* planner() const;
  TreeSnapshot tree() const;
  PathSnapshot path() const;
  /// Version of the last map change reported (0: none).
  uint64_t mapVersion() const { return map_version_; }

 private:
  struct ActiveQuery;

  /// The space, objective and planner of `query`, rooted at `start` (throws on a bad query).
  std::unique_ptr<ActiveQuery> buildQuery(const PlanningQuery& query, octomap::OcTree& map,
                                          const Eigen::Vector3d& start);
  /// Re-checks the tree against the changed map; cancels and restarts when the way is blocked.
  void recheckTree(const std::optional<Eigen::Vector3d>& vehicle, double now);
  /// Under max_tree_size without a solution nothing prunes the tree: regrow it from its root.
  void regrowIfFullWithoutSolution();
  void answerWaypointRequest();
  /// Whether the next waypoint waits (detour_hold); ends the hold, logged, once a way back
  /// under detour_factor is found, the tree is full or the hold is over.
  bool holdingForDetour();
  /// Whether the hull passes from `vehicle` to the tree's `root` the way the controller will
  /// drive: through the waypoint it still heads for, if any (forgotten once within tolerance).
  bool vehicleReachesRoot(const Eigen::Vector3d& vehicle, const Eigen::Vector3d& root);
  void cancel(uint64_t waypoint_id, CancelReason reason, const std::string& text);

  SessionOptions options_;
  std::shared_ptr<ReplicaDistanceField> field_;
  std::unique_ptr<ActiveQuery> query_;
  std::optional<WaypointRequest> pending_request_;  // for the active query
  std::optional<WaypointRequest> early_request_;    // for a query not started (yet)
  double early_request_since_ = 0.0;                // s, when that query's first request came
  uint64_t next_waypoint_id_ = 1;
  uint64_t map_version_ = 0;
  // What changed in the map since the tree was last re-checked.
  Eigen::AlignedBox3d changed_region_;
  bool recheck_everything_ = true;  // a full map arrived: no box says what changed
  Outbox outbox_;
  double now_ = 0.0;  // of the latest slice
};

}  // namespace auv::planning
