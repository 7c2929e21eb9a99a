#include "auv/planning/planning_session.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

#include <octomap/OcTree.h>
#include <ompl/base/PlannerTerminationCondition.h>
#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/ScopedState.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/objectives/PathLengthOptimizationObjective.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>

#include "auv/planning/visibility_cost.h"

namespace auv::planning {

namespace ob = ompl::base;

/// The distance field of the caller's map: forwards to an OctomapDistanceField that is rebuilt
/// when a full map replaces the tree or a query changes the covered box, so the space
/// information and objective of the active query keep one field for their whole life.
class ReplicaDistanceField : public DistanceField {
 public:
  ReplicaDistanceField(double resolution, double max_distance)
      : resolution_(resolution), max_distance_(max_distance) {}

  void rebuild(octomap::OcTree* tree, const OctomapDistanceFieldOptions& options) {
    options_ = options;
    field_ = std::make_unique<OctomapDistanceField>(tree, options);
    ++revision_;
  }
  void rebuild(octomap::OcTree* tree) { rebuild(tree, options_); }
  void update() {
    field_->update();
    ++revision_;
  }
  double distance(const Eigen::Vector3d& position) const override {
    return field_ ? field_->distance(position) : max_distance_;
  }
  double maxDistance() const override { return max_distance_; }
  double altitude(const Eigen::Vector3d& position, double reach) const override {
    return field_ ? field_->altitude(position, reach) : std::numeric_limits<double>::infinity();
  }
  double resolution() const override { return resolution_; }
  std::uint64_t revision() const override { return revision_; }

 private:
  double resolution_;
  double max_distance_;
  OctomapDistanceFieldOptions options_;
  std::unique_ptr<OctomapDistanceField> field_;
  std::uint64_t revision_ = 0;
};

struct PlanningSession::ActiveQuery {
  PlanningQuery query;
  ob::SpaceInformationPtr si;
  ob::ProblemDefinitionPtr pdef;
  std::shared_ptr<WaypointPlanner> planner;
  Eigen::Vector3d goal = Eigen::Vector3d::Zero();
  double time_budget = 0.0;
  // Last time the tree had a solution, or the query (re)started: the budget runs from here, so
  // an obstacle that removes the solution mid-mission gets a full budget to be planned around.
  double solved_at = 0.0;
  uint64_t active_waypoint_id = 0;  // 0: none issued since the (re)start
  PlannedWaypoint active_waypoint;  // the one sent as active_waypoint_id, for repeated requests
  // The waypoint the vehicle is still heading for when the active one was sent (the mission
  // handler asks early): until the vehicle reaches it, its way to the root passes through it.
  std::optional<Eigen::Vector3d> approach_via;
  uint64_t checked_revision = 0;  // field revision the tree was last re-checked against
  bool no_solution_reported = false;
  uint64_t earlier_iterations = 0;  // iterations of the trees dropped by restarts
  // detour_hold: the best cost before the map change that made it jump, and until when the
  // next waypoint waits for a way back under detour_factor × it (0: no hold).
  double cost_before_detour = 0.0;
  double hold_until = 0.0;
};

namespace {

void setPosition(ob::State* state, const Eigen::Vector3d& position) {
  auto* values = state->as<ob::RealVectorStateSpace::StateType>()->values;
  for (int i = 0; i < 3; ++i) values[i] = position[i];
}

std::string depthText(double value) {
  std::ostringstream text;
  text << value << " m";
  return text.str();
}

/// The space's z-range becomes the bounds' intersected with the query's depth band (3-D
/// planning). Throws PlanningConfigError for an inverted band, one outside the bounds, or a
/// goal outside it. The start is not checked: enforceBounds() brings it into the band.
void applyBand(const PlanningQuery& query, PlanningSpaceOptions& space) {
  if (!std::isfinite(query.min_depth) || !std::isfinite(query.max_depth) ||
      !(query.min_depth < query.max_depth)) {
    throw PlanningConfigError("depth band: min_depth " + depthText(query.min_depth) +
                              " must be above max_depth " + depthText(query.max_depth) +
                              " (both 0: no band)");
  }
  const double low = std::max(space.min_corner.z(), query.min_depth);
  const double high = std::min(space.max_corner.z(), query.max_depth);
  if (!(low < high)) {
    throw PlanningConfigError("depth band [" + depthText(query.min_depth) + ", " +
                              depthText(query.max_depth) + "] is outside the bounds' z-range [" +
                              depthText(space.min_corner.z()) + ", " +
                              depthText(space.max_corner.z()) + "]");
  }
  if (query.goal.z() < low || query.goal.z() > high) {
    throw PlanningConfigError("goal depth " + depthText(query.goal.z()) +
                              " is outside the depth band [" + depthText(low) + ", " +
                              depthText(high) + "]");
  }
  space.min_corner.z() = low;
  space.max_corner.z() = high;
}

}  // namespace

const config::OptionTable<SessionOptions>& SessionOptions::table() {
  using config::Range;
  using O = SessionOptions;
  static const config::OptionTable<O> kTable = {
      {"range", &O::range, "RRT* extension length (delta)", "m", Range::closed(0.05, 100.0)},
      {"goal_bias", &O::goal_bias,
       "probability of sampling the goal region: half these draws the goal, half a state "
       "within the goal tolerance of it",
       "", Range::closed(0, 1)},
      {"narrow_passage_bias", &O::narrow_passage_bias,
       "share of random states drawn by OMPL's bridge test, which finds narrow passages "
       "(gaps) that uniform sampling rarely hits; 0 = uniform only (the paper)",
       "", Range::closed(0, 1)},
      {"rewire_factor", &O::rewire_factor, "RRT* rewiring radius factor", "",
       Range::closed(1.0, 10.0)},
      {"visibility_weight", &O::visibility_weight,
       "weight w of the Eq. (1) visibility term (0: path length)", "", Range::closed(0, 100)},
      {"fixed_depth", &O::fixed_depth,
       "plan in the horizontal plane at the start depth even for 3-D queries"},
      {"map_resolution", &O::map_resolution,
       "leaf size map updates must have (others are rejected)", "m", Range::closed(0.01, 10.0)},
      {"max_distance", &O::max_distance, "distance field clamp (>= 2 d_e keeps Eq. (1) exact)", "m",
       Range::closed(0.5, 100.0)},
      {"field_margin", &O::field_margin, "distance field box = query bounds grown by this", "m",
       Range::closed(0.0, 100.0)},
      {"iteration_budget", &O::iteration_budget, "length of one planning slice", "s",
       Range::closed(0.005, 10.0)},
      {"max_tree_size", &O::max_tree_size,
       "tree size at which growing pauses until a waypoint prunes it", "nodes",
       Range::closed(100, 1e7)},
      {"default_time_budget", &O::default_time_budget,
       "time to a first solution when a query gives 0 (then NO_SOLUTION cancel)", "s",
       Range::closed(0.1, 3600.0)},
      {"waypoint_speed", &O::waypoint_speed, "surge speed asked for towards waypoints", "m/s",
       Range::closed(0.01, 10.0)},
      {"waypoint_tolerance", &O::waypoint_tolerance,
       "distance at which a waypoint counts as reached", "m", Range::closed(0.01, 10.0)},
      {"replanning",
       &O::replanning,
       "on a map change: repair the anytime tree (the paper), or plan anew from the root with "
       "OMPL's RRTstar (scratch) or with the repair planner's tree restarted (restart): the "
       "campaign's baselines",
       "",
       {},
       {"repair", "scratch", "restart"}},
      {"detour_hold", &O::detour_hold,
       "when a map change raises the best path's cost above detour_factor times what it was, "
       "the next waypoint waits up to this long for a shorter way (0: never)",
       "s", Range::closed(0, 600)},
      {"detour_factor", &O::detour_factor, "cost ratio that starts a detour_hold", "",
       Range::closed(1.0, 100.0)},
  };
  return kTable;
}

void SessionOptions::check() const {
  config::checkOptions<PlanningConfigError>(*this, table());
  clearance.check();
  if (goal_bias + narrow_passage_bias > 1.0) {
    throw PlanningConfigError("goal_bias + narrow_passage_bias must be <= 1 (got " +
                              std::to_string(goal_bias) + " + " +
                              std::to_string(narrow_passage_bias) + ")");
  }
}

bool hullPassesAlong(const DistanceField& field, const Eigen::Vector3d& from,
                     const Eigen::Vector3d& to, double hull_radius, double step) {
  const int steps = std::max(1, static_cast<int>(std::ceil((to - from).norm() / step)));
  double previous = field.distance(from);
  bool escaping = previous < hull_radius;
  for (int i = 1; i <= steps; ++i) {
    const double distance = field.distance(from + (to - from) * (static_cast<double>(i) / steps));
    if (distance >= hull_radius) {
      escaping = false;
    } else if (!escaping || distance < previous) {
      return false;
    }
    previous = distance;
  }
  return true;
}

PlanningSession::PlanningSession(const SessionOptions& options) : options_(options) {
  options_.check();
  field_ = std::make_shared<ReplicaDistanceField>(options_.map_resolution, options_.max_distance);
}

PlanningSession::~PlanningSession() = default;

void PlanningSession::onFullMap(octomap::OcTree& map, uint64_t version) {
  map_version_ = version;
  if (query_) field_->rebuild(&map);  // a full map is a new tree
  recheck_everything_ = true;
}

void PlanningSession::onMapIncrement(const Eigen::Vector3d& changed_min,
                                     const Eigen::Vector3d& changed_max, uint64_t version) {
  map_version_ = version;
  if (query_) field_->update();
  if ((changed_min.array() < changed_max.array()).all()) {
    changed_region_.extend(Eigen::AlignedBox3d(changed_min, changed_max));
  } else if (!(changed_min.array() > changed_max.array()).any()) {
    recheck_everything_ = true;  // a flat box: not filled in by the sender, so unknown
  }                              // else an empty update: nothing changed
}

bool PlanningSession::startQuery(const PlanningQuery& query, octomap::OcTree& map,
                                 const std::optional<Eigen::Vector3d>& vehicle, double now) {
  if (query_ && query_->active_waypoint_id != 0) {
    cancel(query_->active_waypoint_id, CancelReason::QUERY_REPLACED,
           "query " + std::to_string(query.query_id) + " replaces it");
  }
  query_.reset();
  pending_request_.reset();  // for the replaced query
  if (early_request_ && early_request_->query_id == query.query_id) {
    pending_request_ = early_request_;  // it overtook this query
  }
  early_request_.reset();
  std::unique_ptr<ActiveQuery> active;
  try {
    active = buildQuery(query, map, vehicle ? *vehicle : query.start);
  } catch (const std::exception& error) {
    // The cancel names the refused query.
    outbox_.messages.emplace_back(WaypointCancel{0, query.query_id, CancelReason::PLANNER_ERROR,
                                                 std::string("query rejected: ") + error.what()});
    pending_request_.reset();
    return false;
  }
  active->time_budget = query.time_budget > 0.0 ? query.time_budget : options_.default_time_budget;
  active->solved_at = now;
  active->checked_revision = field_->revision();
  changed_region_.setEmpty();  // the new tree is grown on the map as it is now
  recheck_everything_ = false;
  query_ = std::move(active);
  return true;
}

std::unique_ptr<PlanningSession::ActiveQuery> PlanningSession::buildQuery(
    const PlanningQuery& query, octomap::OcTree& map, const Eigen::Vector3d& start) {
  auto active = std::make_unique<ActiveQuery>();
  active->query = query;
  if (query.query_id == 0) throw PlanningConfigError("query_id 0 is invalid");
  if (!(query.goal_tolerance > 0.0)) throw PlanningConfigError("goal_tolerance must be > 0");
  PlanningSpaceOptions space;
  space.min_corner = query.bounds_min;
  space.max_corner = query.bounds_max;
  if (query.fixed_depth) {
    space.fixed_depth = *query.fixed_depth;
  } else if (options_.fixed_depth) {
    space.fixed_depth = start.z();
  }
  space.check();
  // The field covers the bounds, not just the band: Eq. (1) and the clearance see the rock
  // outside the band too.
  OctomapDistanceFieldOptions field_options;
  field_options.max_distance = options_.max_distance;
  field_options.min_corner = space.min_corner - Eigen::Vector3d::Constant(options_.field_margin);
  field_options.max_corner = space.max_corner + Eigen::Vector3d::Constant(options_.field_margin);
  if (!space.fixed_depth && query.hasBand()) applyBand(query, space);
  field_->rebuild(&map, field_options);
  ClearanceOptions clearance = options_.clearance;
  clearance.min_altitude = query.min_altitude;
  active->si = makeSpaceInformation(space, field_, clearance);

  ob::OptimizationObjectivePtr objective;
  if (query.objective == PlanningObjective::PATH_LENGTH) {
    objective = std::make_shared<ob::PathLengthOptimizationObjective>(active->si);
  } else {
    VisibilityObjectiveOptions visibility;
    visibility.cost.expected_distance = query.expected_distance;
    visibility.cost.admissible_range = query.admissible_range;
    visibility.visibility_weight = options_.visibility_weight;
    visibility.check();
    objective = std::make_shared<VisibilityObjective>(active->si, field_, visibility);
  }
  active->goal = query.goal;
  if (space.fixed_depth) active->goal.z() = *space.fixed_depth;
  ob::ScopedState<> start_state(active->si);
  ob::ScopedState<> goal_state(active->si);
  setPosition(start_state.get(), start);
  active->si->enforceBounds(start_state.get());
  setPosition(goal_state.get(), active->goal);
  active->pdef = std::make_shared<ob::ProblemDefinition>(active->si);
  active->pdef->setStartAndGoalStates(start_state, goal_state, query.goal_tolerance);
  active->pdef->setOptimizationObjective(objective);
  const TreeSettings tree{options_.range, options_.goal_bias, options_.narrow_passage_bias,
                          options_.rewire_factor, query.goal_tolerance};
  active->planner = makeWaypointPlanner(replanningFromName(options_.replanning), tree, active->si,
                                        active->pdef, start_state.get());
  return active;
}

void PlanningSession::onWaypointRequest(const WaypointRequest& request, double now) {
  if (!query_ || query_->query.query_id != request.query_id) {
    if (query_ && request.query_id < query_->query.query_id) {
      outbox_.warnings.push_back("waypoint request for query " + std::to_string(request.query_id) +
                                 ", older than the one planned (" +
                                 std::to_string(query_->query.query_id) + ")");
      return;
    }
    // Queries and requests travel on different topics: a mission handler's first request can
    // overtake its query. Kept for the next query to start, used if it is that one; unless
    // it cannot be in flight any more.
    const bool repeated = early_request_ && early_request_->query_id == request.query_id;
    if (request.reached_waypoint_id != 0 ||
        (repeated && now - early_request_since_ >= kLostQueryAfter)) {
      early_request_.reset();
      outbox_.messages.emplace_back(WaypointCancel{
          0, request.query_id, CancelReason::UNKNOWN_QUERY,
          "this planner has no query " + std::to_string(request.query_id) +
              (request.reached_waypoint_id != 0 ? " (it restarted since the query began)"
                                                : " (the query was lost)")});
      return;
    }
    if (!repeated) early_request_since_ = now;
    early_request_ = request;
    return;
  }
  if (query_->active_waypoint_id != 0 &&
      request.reached_waypoint_id != query_->active_waypoint_id) {
    // The vehicle has not reached the active waypoint: a repeated request whose answer was
    // lost or crossed it. Popping again would skip a waypoint; send the active one again.
    PlannedWaypoint again = query_->active_waypoint;
    again.repeat = true;
    outbox_.messages.emplace_back(again);
    return;
  }
  pending_request_ = request;
  answerWaypointRequest();  // otherwise a later slice answers once a solution exists
}

bool PlanningSession::vehicleReachesRoot(const Eigen::Vector3d& vehicle,
                                         const Eigen::Vector3d& root) {
  ActiveQuery& q = *query_;
  // The controller drives to the waypoint it has before the one just sent: checking the
  // straight line to the root instead would cancel good waypoints round corners.
  if (q.approach_via && (vehicle - *q.approach_via).norm() <= options_.waypoint_tolerance) {
    q.approach_via.reset();
  }
  const double hull = options_.clearance.hull_radius;
  const double step = 0.5 * options_.map_resolution;
  if (!q.approach_via) return hullPassesAlong(*field_, vehicle, root, hull, step);
  return hullPassesAlong(*field_, vehicle, *q.approach_via, hull, step) &&
         hullPassesAlong(*field_, *q.approach_via, root, hull, step);
}

bool PlanningSession::planSlice(const std::optional<Eigen::Vector3d>& vehicle, double now) {
  now_ = now;
  if (!query_) return false;
  ActiveQuery& q = *query_;
  // Re-check the tree only when the map changed: between changes the tree stays valid, and the
  // vehicle moves along the root edge the tree already holds.
  if (field_->revision() != q.checked_revision && q.planner->rootState() != nullptr) {
    recheckTree(vehicle, now);
  }
  regrowIfFullWithoutSolution();
  if (q.planner->treeSize() >= options_.max_tree_size) return false;
  // Stops at max_tree_size too: one slice may add thousands of nodes.
  const WaypointPlanner& planner = *q.planner;
  const std::size_t max_size = options_.max_tree_size;
  q.planner->solve(ob::plannerOrTerminationCondition(
      ob::timedPlannerTerminationCondition(options_.iteration_budget),
      ob::PlannerTerminationCondition(
          [&planner, max_size] { return planner.treeSize() >= max_size; })));
  return true;
}

void PlanningSession::recheckTree(const std::optional<Eigen::Vector3d>& vehicle, double now) {
  ActiveQuery& q = *query_;
  q.checked_revision = field_->revision();
  ob::ScopedState<> vehicle_state(q.si);
  setPosition(vehicle_state.get(), vehicle ? *vehicle : q.query.start);
  q.si->enforceBounds(vehicle_state.get());  // also puts it on the fixed depth
  // Only edges near what changed can change (the mapping component reports the box of every
  // increment): within the clearance for validity, within the band of Eq. (1) for costs.
  // A seabed appearing below reaches up min_altitude + clearance (the column check).
  const double influence = std::max({options_.clearance.clearance() + q.query.min_altitude,
                                     q.query.expected_distance + 0.5 * q.query.admissible_range}) +
                           options_.map_resolution;
  const double cost_before = q.planner->bestCost().value();
  UpdateResult result = recheck_everything_
                            ? q.planner->updateTree(nullptr)
                            : q.planner->updateTree(nullptr, changed_region_, influence);
  const double cost_after = q.planner->bestCost().value();
  if (options_.detour_hold > 0.0 && q.hold_until <= now && std::isfinite(cost_before) &&
      cost_after > options_.detour_factor * cost_before) {
    q.cost_before_detour = cost_before;
    q.hold_until = now + options_.detour_hold;
    std::ostringstream text;
    text << "map version " << map_version_ << " raised the best path's cost from " << cost_before
         << " to " << cost_after << ": the next waypoint waits up to " << options_.detour_hold
         << " s for a shorter way (detour_hold)";
    outbox_.warnings.push_back(text.str());
  }
  recheck_everything_ = false;
  changed_region_.setEmpty();
  // The vehicle drifts off the planned edges by its tracking error, which the safety margin
  // is there to absorb: the way to the root is blocked only when the hull itself would touch.
  result.vehicle_to_root_blocked = !vehicleReachesRoot(statePosition(vehicle_state.get()),
                                                       statePosition(q.planner->rootState()));
  // Without an active waypoint the root is where the vehicle holds (the query's start or the
  // waypoint just reached): too close to a newly seen wall is no reason to restart there, and
  // the motion validator lets the tree leave it by moving away from the wall.
  if (!result.needsRestart() || q.active_waypoint_id == 0) return;
  const Eigen::Vector3d root = statePosition(q.planner->rootState());
  std::ostringstream text;
  text << (result.root_in_collision ? "root" : "segment vehicle -> root") << " at (" << root.x()
       << ", " << root.y() << ", " << root.z() << ") closer than "
       << (result.root_in_collision ? options_.clearance.clearance()
                                    : options_.clearance.hull_radius)
       << " m to the map (version " << map_version_ << ")";
  cancel(q.active_waypoint_id,
         result.root_in_collision ? CancelReason::ROOT_IN_COLLISION
                                  : CancelReason::APPROACH_IN_COLLISION,
         text.str());
  q.earlier_iterations += q.planner->iterations();  // reset() zeroes the core's count
  q.planner->reset(vehicle_state.get());
  q.active_waypoint_id = 0;
  q.approach_via.reset();
  q.solved_at = now;
}

void PlanningSession::regrowIfFullWithoutSolution() {
  ActiveQuery& q = *query_;
  if (q.planner->treeSize() < options_.max_tree_size || q.planner->hasSolution() ||
      q.planner->rootState() == nullptr) {
    return;
  }
  // Full without a solution: only popWaypoint() (which needs a solution) or a restart would
  // prune it, so growing would never resume, even once the map opens a way. Grow a fresh
  // tree from the same root: the active waypoint stays valid.
  ob::ScopedState<> root(q.si);
  q.si->copyState(root.get(), q.planner->rootState());
  q.earlier_iterations += q.planner->iterations();
  q.planner->reset(root.get());
}

void PlanningSession::finishSlice(double now) {
  now_ = now;
  if (!query_) return;
  answerWaypointRequest();
  ActiveQuery& q = *query_;
  if (q.planner->hasSolution()) {
    q.solved_at = now;
    q.no_solution_reported = false;  // a later loss of every solution is reported again
    return;
  }
  const double unsolved = now - q.solved_at;
  if (!q.no_solution_reported && unsolved > q.time_budget) {
    q.no_solution_reported = true;
    std::ostringstream text;
    text << "no solution for " << unsolved << " s (budget " << q.time_budget << " s), "
         << q.planner->treeSize() << " nodes";
    cancel(q.active_waypoint_id, CancelReason::NO_SOLUTION, text.str());
  }
}

void PlanningSession::answerWaypointRequest() {
  if (!pending_request_ || !query_ || !query_->planner->hasSolution() ||
      pending_request_->query_id != query_->query.query_id) {
    return;
  }
  ActiveQuery& q = *query_;
  if (holdingForDetour()) return;
  const Eigen::Vector3d from = statePosition(q.planner->rootState());
  ob::ScopedState<> waypoint_state(q.si);
  if (!q.planner->popWaypoint(waypoint_state.get())) return;  // the root is the goal already
  PlannedWaypoint waypoint;
  waypoint.waypoint_id = next_waypoint_id_++;
  waypoint.query_id = q.query.query_id;
  waypoint.position = statePosition(waypoint_state.get());
  waypoint.heading = std::atan2(waypoint.position.y() - from.y(), waypoint.position.x() - from.x());
  waypoint.speed = options_.waypoint_speed;
  waypoint.tolerance = options_.waypoint_tolerance;
  waypoint.is_final = (waypoint.position - q.goal).norm() <= q.query.goal_tolerance;
  q.active_waypoint_id = waypoint.waypoint_id;
  q.active_waypoint = waypoint;
  q.approach_via = from;
  pending_request_.reset();
  outbox_.messages.emplace_back(waypoint);
}

bool PlanningSession::holdingForDetour() {
  ActiveQuery& q = *query_;
  if (q.hold_until <= 0.0) return false;
  const double cost = q.planner->bestCost().value();
  const bool way_back = cost <= options_.detour_factor * q.cost_before_detour;
  // The tree grows only while not full, and only a waypoint (which the hold withholds) prunes it.
  const bool full = q.planner->treeSize() >= options_.max_tree_size;
  if (!way_back && !full && now_ < q.hold_until) return true;
  std::ostringstream text;
  if (way_back) {
    text << "found a way of cost " << cost;
  } else {
    text << (full ? "the tree is full (max_tree_size)" : "no shorter way within detour_hold")
         << ": taking the detour of cost " << cost;
  }
  text << " (" << q.cost_before_detour << " before the map change)";
  outbox_.warnings.push_back(text.str());
  q.hold_until = 0.0;
  return false;
}

void PlanningSession::cancel(uint64_t waypoint_id, CancelReason reason, const std::string& text) {
  outbox_.messages.emplace_back(
      WaypointCancel{waypoint_id, query_ ? query_->query.query_id : 0, reason, text});
}

PlanningSession::Outbox PlanningSession::takeOutbox() { return std::exchange(outbox_, Outbox{}); }

uint64_t PlanningSession::queryId() const { return query_ ? query_->query.query_id : 0; }

uint64_t PlanningSession::activeWaypointId() const {
  return query_ ? query_->active_waypoint_id : 0;
}

bool PlanningSession::growing() const {
  return query_ != nullptr && query_->planner->treeSize() < options_.max_tree_size;
}

const WaypointPlanner* PlanningSession::planner() const {
  return query_ ? query_->planner.get() : nullptr;
}

TreeSnapshot PlanningSession::tree() const {
  TreeSnapshot tree;
  if (!query_) return tree;
  const ActiveQuery& q = *query_;
  q.planner->snapshot(tree);
  for (std::size_t i = 0; i < tree.nodes.size(); ++i) {
    if ((tree.nodes[i] - q.goal).norm() <= q.query.goal_tolerance) {
      tree.solution_indices.push_back(static_cast<int32_t>(i));
    }
  }
  tree.iterations = q.earlier_iterations + q.planner->iterations();
  return tree;
}

PathSnapshot PlanningSession::path() const {
  PathSnapshot path;
  if (!query_) return path;
  for (const ob::State* state : query_->planner->bestPath()) {
    path.positions.push_back(statePosition(state));
  }
  path.cost = query_->planner->bestCost().value();
  return path;
}

}  // namespace auv::planning
