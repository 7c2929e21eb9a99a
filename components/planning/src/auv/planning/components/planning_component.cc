#include "auv/planning/components/planning_component.h"
#include "auv/interfaces/msg_time.h"

#include <chrono>
#include <cmath>
#include <functional>
#include <sstream>

#include <ompl/base/PlannerTerminationCondition.h>
#include <ompl/base/ScopedState.h>
#include <ompl/base/objectives/PathLengthOptimizationObjective.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>

#include "auv/mapping/map_replica.h"

namespace auv::planning {

/// The distance field of the replica: forwards to an OctomapDistanceField that is rebuilt when
/// a FULL map replaces the tree or a query changes the covered box, so the space information
/// and objective of the active query keep one field for their whole life.
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
  double resolution() const override { return resolution_; }
  std::uint64_t revision() const override { return revision_; }

 private:
  double resolution_;
  double max_distance_;
  OctomapDistanceFieldOptions options_;
  std::unique_ptr<OctomapDistanceField> field_;
  std::uint64_t revision_ = 0;
};

struct PlanningComponent::ActiveQuery {
  msg::PlannerQuery query;
  ompl::base::SpaceInformationPtr si;
  ompl::base::ProblemDefinitionPtr pdef;
  std::shared_ptr<OnlineRRTstar> planner;
  Eigen::Vector3d goal = Eigen::Vector3d::Zero();
  double time_budget = 0.0;
  // Last time the tree had a solution, or the query (re)started: the budget runs from here, so
  // an obstacle that removes the solution mid-mission gets a full budget to be planned around.
  int64_t solved_ns = 0;
  uint64_t active_waypoint_id = 0;  // 0: none issued since the (re)start
  msg::Waypoint active_waypoint;    // the one sent as active_waypoint_id, for repeated requests
  // The waypoint the vehicle is still heading for when the active one was sent (the mission
  // handler asks early): until the vehicle reaches it, its way to the root passes through it.
  std::optional<Eigen::Vector3d> approach_via;
  uint64_t checked_revision = 0;  // field revision the tree was last re-checked against
  bool no_solution_reported = false;
  uint64_t earlier_iterations = 0;  // iterations of the trees dropped by restarts
};

namespace {

namespace ob = ompl::base;

Eigen::Vector3d toVector(const msg::Point& p) { return {p.x(), p.y(), p.z()}; }

msg::Point toPoint(const Eigen::Vector3d& v) {
  msg::Point p;
  p.x(v.x());
  p.y(v.y());
  p.z(v.z());
  return p;
}

void setStamp(msg::Header& header, int64_t ns) { header.stamp(interfaces::toMsgTime(ns)); }

void setPosition(ob::State* state, const Eigen::Vector3d& position) {
  auto* values = state->as<ob::RealVectorStateSpace::StateType>()->values;
  for (int i = 0; i < 3; ++i) values[i] = position[i];
}

}  // namespace

PlanningComponent::PlanningComponent() = default;

PlanningComponent::~PlanningComponent() { deactivate(); }

void PlanningComponent::configure(interfaces::Node& node) {
  node_ = &node;
  auto& p = node.parameters();
  auto& o = options_;
  o.range = p.declare<double>("range", o.range,
                              {"RRT* extension length (delta)", "m", 0.05, 100.0, {}, true});
  o.goal_bias = p.declare<double>("goal_bias", o.goal_bias,
                                  {"probability of sampling the goal", "", 0.0, 1.0, {}, true});
  o.narrow_passage_bias = p.declare<double>(
      "narrow_passage_bias", o.narrow_passage_bias,
      {"share of random states drawn by OMPL's bridge test, which finds narrow passages "
       "(gaps) that uniform sampling rarely hits; 0 = uniform only (the paper)",
       "",
       0.0,
       1.0,
       {},
       true});
  o.rewire_factor = p.declare<double>("rewire_factor", o.rewire_factor,
                                      {"RRT* rewiring radius factor", "", 1.0, 10.0, {}, true});
  o.clearance.hull_radius =
      p.declare<double>("hull_radius", o.clearance.hull_radius,
                        {"radius of the sphere enclosing the hull", "m", 0.0, 20.0, {}, true});
  o.clearance.safety_margin =
      p.declare<double>("safety_margin", o.clearance.safety_margin,
                        {"clearance kept on top of hull_radius", "m", 0.0, 20.0, {}, true});
  o.visibility_weight = p.declare<double>(
      "visibility_weight", o.visibility_weight,
      {"weight w of the Eq. (1) visibility term (0: path length)", "", 0.0, 100.0, {}, true});
  o.fixed_depth =
      p.declare<bool>("fixed_depth", o.fixed_depth,
                      {"plan in the horizontal plane at the start depth even for 3-D queries",
                       "",
                       {},
                       {},
                       {},
                       true});
  o.map_resolution = p.declare<double>(
      "map_resolution", o.map_resolution,
      {"leaf size map updates must have (others are rejected)", "m", 0.01, 10.0, {}, true});
  o.max_distance = p.declare<double>(
      "max_distance", o.max_distance,
      {"distance field clamp (>= 2 d_e keeps Eq. (1) exact)", "m", 0.5, 100.0, {}, true});
  o.field_margin = p.declare<double>(
      "field_margin", o.field_margin,
      {"distance field box = query bounds grown by this", "m", 0.0, 100.0, {}, true});
  o.iteration_budget =
      p.declare<double>("iteration_budget", o.iteration_budget,
                        {"length of one planning slice", "s", 0.005, 10.0, {}, true});
  o.max_tree_size = static_cast<std::size_t>(p.declare<int64_t>(
      "max_tree_size", static_cast<int64_t>(o.max_tree_size),
      {"tree size at which growing pauses until a waypoint prunes it", "", 100.0, 1e7, {}, true}));
  o.default_time_budget =
      p.declare<double>("default_time_budget", o.default_time_budget,
                        {"time to a first solution when a query gives 0 (then NO_SOLUTION cancel)",
                         "s",
                         0.1,
                         3600.0,
                         {},
                         true});
  o.path_rate = p.declare<double>("path_rate", o.path_rate,
                                  {"rate of planner/path", "Hz", 0.01, 100.0, {}, true});
  o.tree_rate = p.declare<double>("tree_rate", o.tree_rate,
                                  {"rate of planner/tree", "Hz", 0.01, 100.0, {}, true});
  o.waypoint_speed =
      p.declare<double>("waypoint_speed", o.waypoint_speed,
                        {"surge speed asked for towards waypoints", "m/s", 0.01, 10.0, {}, true});
  o.waypoint_tolerance = p.declare<double>(
      "waypoint_tolerance", o.waypoint_tolerance,
      {"distance at which a waypoint counts as reached", "m", 0.01, 10.0, {}, true});
  o.full_request_period =
      p.declare<double>("full_request_period", o.full_request_period,
                        {"period of map/request_full calls while the replica misses an update",
                         "s",
                         0.1,
                         60.0,
                         {},
                         true});
  o.map_id = p.declare<std::string>("map_id", o.map_id,
                                    {"map instance followed on map/update", "", {}, {}, {}, true});
  o.world_frame = p.declare<std::string>("world_frame", o.world_frame,
                                         {"frame of published poses (NED)", "", {}, {}, {}, true});
  o.clearance.check();
  if (o.goal_bias + o.narrow_passage_bias > 1.0) {
    throw PlanningConfigError("goal_bias + narrow_passage_bias must be <= 1 (got " +
                              std::to_string(o.goal_bias) + " + " +
                              std::to_string(o.narrow_passage_bias) + ")");
  }

  replica_ = std::make_unique<mapping::MapReplica>(o.map_id, o.map_resolution);
  field_ = std::make_shared<ReplicaDistanceField>(o.map_resolution, o.max_distance);

  waypoint_pub_ = node.createPublisher<msg::Waypoint>("planner/waypoint", interfaces::commandQos());
  cancel_pub_ =
      node.createPublisher<msg::WaypointCancel>("planner/cancel", interfaces::commandQos());
  path_pub_ = node.createPublisher<msg::Path>("planner/path", interfaces::viewingQos());
  tree_pub_ = node.createPublisher<msg::PlannerTree>("planner/tree", interfaces::viewingQos());
  full_client_ = node.createClient<msg::TriggerRequest, msg::TriggerReply>("map/request_full");
  map_sub_ = node.createSubscription<msg::OctomapUpdate>(
      "map/update", interfaces::mapQos(),
      std::function<void(const msg::OctomapUpdate&)>(
          [this](const msg::OctomapUpdate& u) { onMapUpdate(u); }));
  odometry_sub_ = node.createSubscription<msg::Odometry>(
      "nav/odometry", interfaces::stateQos(),
      std::function<void(const msg::Odometry&)>([this](const msg::Odometry& o) { onOdometry(o); }));
  query_sub_ = node.createSubscription<msg::PlannerQuery>(
      "mission/query", interfaces::commandQos(),
      std::function<void(const msg::PlannerQuery&)>(
          [this](const msg::PlannerQuery& q) { onQuery(q); }));
  request_sub_ = node.createSubscription<msg::WaypointRequest>(
      "planner/waypoint_request", interfaces::commandQos(),
      std::function<void(const msg::WaypointRequest&)>(
          [this](const msg::WaypointRequest& r) { onWaypointRequest(r); }));
}

void PlanningComponent::activate() {
  full_request_timer_ =
      node_->createTimer(options_.full_request_period, [this] { requestFullMapIfNeeded(); });
  running_ = true;
  thread_ = std::thread([this] { planningLoop(); });
  AUV_INFO(node_->logger(), "planning in slices of " << options_.iteration_budget
                                                     << " s, clearance "
                                                     << options_.clearance.clearance() << " m");
}

void PlanningComponent::deactivate() {
  running_ = false;
  inbox_changed_.notify_all();
  if (thread_.joinable()) thread_.join();
  if (full_request_timer_) full_request_timer_->cancel();
  full_request_timer_.reset();
}

void PlanningComponent::cleanup() {
  map_sub_.reset();
  odometry_sub_.reset();
  query_sub_.reset();
  request_sub_.reset();
  std::lock_guard<std::mutex> lock(mutex_);
  query_.reset();
  waypoint_pub_.reset();
  cancel_pub_.reset();
  path_pub_.reset();
  tree_pub_.reset();
  full_client_.reset();
}

void PlanningComponent::onMapUpdate(const msg::OctomapUpdate& update) {
  {
    std::lock_guard<std::mutex> lock(inbox_mutex_);
    map_inbox_.push_back(update);
  }
  inbox_changed_.notify_all();
}

void PlanningComponent::onOdometry(const msg::Odometry& odometry) {
  std::lock_guard<std::mutex> lock(inbox_mutex_);
  vehicle_position_ = toVector(odometry.pose().pose().position());
}

void PlanningComponent::onQuery(const msg::PlannerQuery& query) {
  {
    std::lock_guard<std::mutex> lock(inbox_mutex_);
    query_inbox_ = query;  // a newer query replaces one not started yet
  }
  inbox_changed_.notify_all();
}

void PlanningComponent::onWaypointRequest(const msg::WaypointRequest& request) {
  // Queued, never answered here: waiting for the planning mutex (a slice, a full map's distance
  // field) would stall the executor, and with it every component composed in this process.
  {
    std::lock_guard<std::mutex> lock(inbox_mutex_);
    request_inbox_.push_back(request);
  }
  inbox_changed_.notify_one();
}

void PlanningComponent::handleWaypointRequest(const msg::WaypointRequest& request) {
  if (!query_ || query_->query.query_id() != request.query_id()) {
    // Queries and requests travel on different topics: a mission handler's first request can
    // overtake its query. Kept for the next query to start, used if it is that one.
    early_request_ = request;
    if (query_ && request.query_id() < query_->query.query_id()) {
      AUV_WARN(node_->logger(), "waypoint request for query " << request.query_id()
                                                              << ", older than the one planned ("
                                                              << query_->query.query_id() << ")");
    }
    return;
  }
  if (query_->active_waypoint_id != 0 &&
      request.reached_waypoint_id() != query_->active_waypoint_id) {
    // The vehicle has not reached the active waypoint: a repeated request whose answer was
    // lost or crossed it. Popping again would skip a waypoint; send the active one again.
    waypoint_pub_->publish(query_->active_waypoint);
    return;
  }
  pending_request_ = request;
  answerWaypointRequest();  // otherwise the planning thread answers once a solution exists
}

void PlanningComponent::planningLoop() {
  bool planning = false;
  while (running_) {
    if (!planning) {
      // Nothing to grow: sleep until a map update or a query arrives (or a stop).
      std::unique_lock<std::mutex> lock(inbox_mutex_);
      inbox_changed_.wait_for(lock, std::chrono::milliseconds(100), [this] {
        return !running_ || !map_inbox_.empty() || query_inbox_.has_value() ||
               !request_inbox_.empty();
      });
    }
    if (!running_) break;
    std::lock_guard<std::mutex> lock(mutex_);
    applyMapUpdates();
    planSlice();
    publishViews();
    planning = query_ != nullptr && query_->planner->treeSize() < options_.max_tree_size;
  }
}

void PlanningComponent::applyMapUpdates() {
  std::deque<msg::OctomapUpdate> updates;
  std::optional<msg::PlannerQuery> query;
  std::deque<msg::WaypointRequest> requests;
  {
    std::lock_guard<std::mutex> lock(inbox_mutex_);
    updates.swap(map_inbox_);
    query.swap(query_inbox_);
    requests.swap(request_inbox_);
  }
  for (const auto& update : updates) applyMapUpdate(update);
  if (query) startQuery(*query);
  for (const auto& request : requests) handleWaypointRequest(request);
}

void PlanningComponent::applyMapUpdate(const msg::OctomapUpdate& update) {
  const mapping::MapReplica::Outcome outcome = replica_->apply(update);
  map_sequence_ = replica_->sequence();
  full_map_needed_ = replica_->needsFullMap();
  if (outcome == mapping::MapReplica::Outcome::REJECTED) {
    AUV_WARN(node_->logger(),
             "map update " << update.sequence_number() << " not applied: " << replica_->error());
  }
  if (outcome != mapping::MapReplica::Outcome::APPLIED) return;
  if (update.kind() == msg::OCTOMAP_UPDATE_FULL) {
    if (query_) field_->rebuild(&replica_->tree());  // a FULL map is a new tree
    recheck_everything_ = true;
    return;
  }
  if (query_) field_->update();
  const Eigen::Vector3d changed_min = toVector(update.changed_min());
  const Eigen::Vector3d changed_max = toVector(update.changed_max());
  if ((changed_min.array() < changed_max.array()).all()) {
    changed_region_.extend(Eigen::AlignedBox3d(changed_min, changed_max));
  } else if (!(changed_min.array() > changed_max.array()).any()) {
    recheck_everything_ = true;  // a flat box: not filled in by the sender, so unknown
  }                              // else an empty update: nothing changed
}

void PlanningComponent::startQuery(const msg::PlannerQuery& query) {
  if (query_ && query_->active_waypoint_id != 0) {
    cancel(query_->active_waypoint_id, msg::CANCEL_REASON_QUERY_REPLACED,
           "query " + std::to_string(query.query_id()) + " replaces it");
  }
  query_.reset();
  pending_request_.reset();  // for the replaced query
  if (early_request_ && early_request_->query_id() == query.query_id()) {
    pending_request_ = early_request_;  // it overtook this query
  }
  early_request_.reset();
  auto active = std::make_unique<ActiveQuery>();
  active->query = query;
  try {
    if (query.query_id() == 0) throw PlanningConfigError("query_id 0 is invalid");
    if (!(query.goal_tolerance() > 0.0)) throw PlanningConfigError("goal_tolerance must be > 0");
    std::optional<Eigen::Vector3d> vehicle;
    {
      std::lock_guard<std::mutex> lock(inbox_mutex_);
      vehicle = vehicle_position_;
    }
    const Eigen::Vector3d start = vehicle ? *vehicle : toVector(query.start().position());
    PlanningSpaceOptions space;
    space.min_corner = toVector(query.bounds_min());
    space.max_corner = toVector(query.bounds_max());
    if (query.fixed_depth()) {
      space.fixed_depth = query.depth();
    } else if (options_.fixed_depth) {
      space.fixed_depth = start.z();
    }
    space.check();
    OctomapDistanceFieldOptions field_options;
    field_options.max_distance = options_.max_distance;
    field_options.min_corner = space.min_corner - Eigen::Vector3d::Constant(options_.field_margin);
    field_options.max_corner = space.max_corner + Eigen::Vector3d::Constant(options_.field_margin);
    field_->rebuild(&replica_->tree(), field_options);
    active->si = makeSpaceInformation(space, field_, options_.clearance);

    ob::OptimizationObjectivePtr objective;
    if (query.objective() == msg::PLANNER_OBJECTIVE_PATH_LENGTH) {
      objective = std::make_shared<ob::PathLengthOptimizationObjective>(active->si);
    } else {
      VisibilityObjectiveOptions visibility;
      visibility.cost.expected_distance = query.expected_distance();
      visibility.cost.admissible_range = query.admissible_range();
      visibility.visibility_weight = options_.visibility_weight;
      visibility.check();
      objective = std::make_shared<VisibilityObjective>(active->si, field_, visibility);
    }
    active->goal = toVector(query.goal().position());
    if (space.fixed_depth) active->goal.z() = *space.fixed_depth;
    ob::ScopedState<> start_state(active->si);
    ob::ScopedState<> goal_state(active->si);
    setPosition(start_state.get(), start);
    active->si->enforceBounds(start_state.get());
    setPosition(goal_state.get(), active->goal);
    active->pdef = std::make_shared<ob::ProblemDefinition>(active->si);
    active->pdef->setStartAndGoalStates(start_state, goal_state, query.goal_tolerance());
    active->pdef->setOptimizationObjective(objective);
    active->planner = std::make_shared<OnlineRRTstar>(active->si);
    active->planner->setRange(options_.range);
    active->planner->setGoalBias(options_.goal_bias);
    active->planner->setNarrowPassageBias(options_.narrow_passage_bias);
    active->planner->setRewireFactor(options_.rewire_factor);
    active->planner->setGoalTolerance(query.goal_tolerance());
    active->planner->setProblemDefinition(active->pdef);
    active->planner->setup();
    // Root the tree at the start even when it is inside the clearance (a vehicle that drifted
    // close to a wall): OMPL's start-state input skips invalid starts and would leave no tree,
    // while the motion validator lets the tree leave such a root by moving away from the wall.
    active->planner->reset(start_state.get());
  } catch (const std::exception& error) {
    query_ = std::move(active);  // for the query id of the cancel
    cancel(0, msg::CANCEL_REASON_PLANNER_ERROR, std::string("query rejected: ") + error.what());
    query_.reset();
    pending_request_.reset();
    return;
  }
  active->time_budget =
      query.time_budget() > 0.0 ? query.time_budget() : options_.default_time_budget;
  active->solved_ns = node_->clock().nowNs();
  active->checked_revision = field_->revision();
  changed_region_.setEmpty();  // the new tree is grown on the map as it is now
  recheck_everything_ = false;
  query_ = std::move(active);
  AUV_INFO(node_->logger(), "planning query " << query.query_id());
}

void PlanningComponent::vehicleState(ob::State* state) const {
  std::optional<Eigen::Vector3d> vehicle;
  {
    std::lock_guard<std::mutex> lock(inbox_mutex_);
    vehicle = vehicle_position_;
  }
  setPosition(state, vehicle ? *vehicle : toVector(query_->query.start().position()));
  query_->si->enforceBounds(state);  // also puts it on the fixed depth
}

bool PlanningComponent::hullPassesAlong(const Eigen::Vector3d& from,
                                        const Eigen::Vector3d& to) const {
  const double step = 0.5 * options_.map_resolution;
  const int steps = std::max(1, static_cast<int>(std::ceil((to - from).norm() / step)));
  // A vehicle already closer than the hull radius (drift, a wall just mapped) may move away:
  // the distance must not shrink until it is clear, as in MapMotionValidator's escapes.
  double previous = field_->distance(from);
  bool escaping = previous < options_.clearance.hull_radius;
  for (int i = 1; i <= steps; ++i) {
    const double distance = field_->distance(from + (to - from) * (static_cast<double>(i) / steps));
    if (distance >= options_.clearance.hull_radius) {
      escaping = false;
    } else if (!escaping || distance < previous) {
      return false;
    }
    previous = distance;
  }
  return true;
}

bool PlanningComponent::vehicleReachesRoot(ActiveQuery& q, const Eigen::Vector3d& vehicle,
                                           const Eigen::Vector3d& root) const {
  // The controller drives to the waypoint it has before the one just sent: checking the
  // straight line to the root instead would cancel good waypoints round corners.
  if (q.approach_via && (vehicle - *q.approach_via).norm() <= options_.waypoint_tolerance) {
    q.approach_via.reset();
  }
  if (!q.approach_via) return hullPassesAlong(vehicle, root);
  return hullPassesAlong(vehicle, *q.approach_via) && hullPassesAlong(*q.approach_via, root);
}

void PlanningComponent::planSlice() {
  if (!query_) return;
  ActiveQuery& q = *query_;
  // Re-check the tree only when the map changed: between changes the tree stays valid, and the
  // vehicle moves along the root edge the tree already holds.
  if (field_->revision() != q.checked_revision && q.planner->root() != nullptr) {
    q.checked_revision = field_->revision();
    ob::ScopedState<> vehicle(q.si);
    vehicleState(vehicle.get());
    // Only edges near what changed can change (the mapping component reports the box of every
    // increment): within the clearance for validity, within the band of Eq. (1) for costs.
    const double influence =
        std::max(options_.clearance.clearance(),
                 q.query.expected_distance() + 0.5 * q.query.admissible_range()) +
        options_.map_resolution;
    UpdateResult result = recheck_everything_
                              ? q.planner->updateTree(nullptr)
                              : q.planner->updateTree(nullptr, changed_region_, influence);
    recheck_everything_ = false;
    changed_region_.setEmpty();
    // The vehicle drifts off the planned edges by its tracking error, which the safety margin
    // is there to absorb: the way to the root is blocked only when the hull itself would touch.
    result.vehicle_to_root_blocked = !vehicleReachesRoot(q, statePosition(vehicle.get()),
                                                         statePosition(q.planner->root()->state));
    // Without an active waypoint the root is where the vehicle holds (the query's start or the
    // waypoint just reached): too close to a newly seen wall is no reason to restart there, and
    // the motion validator lets the tree leave it by moving away from the wall.
    if (result.needsRestart() && q.active_waypoint_id != 0) {
      const Eigen::Vector3d root = statePosition(q.planner->root()->state);
      std::ostringstream text;
      text << (result.root_in_collision ? "root" : "segment vehicle -> root") << " at (" << root.x()
           << ", " << root.y() << ", " << root.z() << ") closer than "
           << (result.root_in_collision ? options_.clearance.clearance()
                                        : options_.clearance.hull_radius)
           << " m to the map (version " << map_sequence_ << ")";
      cancel(q.active_waypoint_id,
             result.root_in_collision ? msg::CANCEL_REASON_ROOT_IN_COLLISION
                                      : msg::CANCEL_REASON_APPROACH_IN_COLLISION,
             text.str());
      q.earlier_iterations += q.planner->iterations();  // reset() zeroes the core's count
      q.planner->reset(vehicle.get());
      q.active_waypoint_id = 0;
      q.approach_via.reset();
      q.solved_ns = node_->clock().nowNs();
    }
  }
  if (q.planner->treeSize() >= options_.max_tree_size && !q.planner->bestSolution() &&
      q.planner->root() != nullptr) {
    // Full without a solution: only popWaypoint() (which needs a solution) or a restart would
    // prune it, so growing would never resume, even once the map opens a way. Grow a fresh
    // tree from the same root: the active waypoint stays valid.
    ob::ScopedState<> root(q.si);
    q.si->copyState(root.get(), q.planner->root()->state);
    q.earlier_iterations += q.planner->iterations();
    q.planner->reset(root.get());
  }
  if (q.planner->treeSize() < options_.max_tree_size) {
    // Stops at max_tree_size too: one slice may add thousands of nodes.
    const OnlineRRTstar& planner = *q.planner;
    const std::size_t max_size = options_.max_tree_size;
    q.planner->solve(ob::plannerOrTerminationCondition(
        ob::timedPlannerTerminationCondition(options_.iteration_budget),
        ob::PlannerTerminationCondition(
            [&planner, max_size] { return planner.treeSize() >= max_size; })));
    ++slices_;
  }
  answerWaypointRequest();
  const int64_t now = node_->clock().nowNs();
  if (q.planner->bestSolution()) {
    q.solved_ns = now;
    q.no_solution_reported = false;  // a later loss of every solution is reported again
    return;
  }
  const double unsolved = 1e-9 * static_cast<double>(now - q.solved_ns);
  if (!q.no_solution_reported && unsolved > q.time_budget) {
    q.no_solution_reported = true;
    std::ostringstream text;
    text << "no solution for " << unsolved << " s (budget " << q.time_budget << " s), "
         << q.planner->treeSize() << " nodes";
    cancel(q.active_waypoint_id, msg::CANCEL_REASON_NO_SOLUTION, text.str());
  }
}

void PlanningComponent::answerWaypointRequest() {
  if (!pending_request_ || !query_ || !query_->planner->bestSolution() ||
      pending_request_->query_id() != query_->query.query_id()) {
    return;
  }
  ActiveQuery& q = *query_;
  const Eigen::Vector3d from = statePosition(q.planner->root()->state);
  ob::ScopedState<> waypoint_state(q.si);
  if (!q.planner->popWaypoint(waypoint_state.get())) return;  // the root is the goal already
  const Eigen::Vector3d position = statePosition(waypoint_state.get());
  msg::Waypoint waypoint;
  setStamp(waypoint.header(), node_->clock().nowNs());
  waypoint.header().frame_id(options_.world_frame);
  waypoint.waypoint_id(next_waypoint_id_++);
  waypoint.query_id(q.query.query_id());
  waypoint.position(toPoint(position));
  waypoint.heading(std::atan2(position.y() - from.y(), position.x() - from.x()));
  waypoint.speed(options_.waypoint_speed);
  waypoint.tolerance(options_.waypoint_tolerance);
  waypoint.is_final((position - q.goal).norm() <= q.query.goal_tolerance());
  q.active_waypoint_id = waypoint.waypoint_id();
  q.active_waypoint = waypoint;
  q.approach_via = from;
  pending_request_.reset();
  waypoint_pub_->publish(waypoint);
}

void PlanningComponent::cancel(uint64_t waypoint_id, int reason, const std::string& text) {
  msg::WaypointCancel message;
  setStamp(message.header(), node_->clock().nowNs());
  message.waypoint_id(waypoint_id);
  message.query_id(query_ ? query_->query.query_id() : 0);
  message.reason(static_cast<msg::CancelReason>(reason));
  message.reason_text(text);
  cancel_pub_->publish(message);
  AUV_WARN(node_->logger(), "cancelled waypoint " << waypoint_id << ": " << text);
}

void PlanningComponent::publishViews() {
  if (!query_) return;
  const ActiveQuery& q = *query_;
  const int64_t now = node_->clock().nowNs();
  if (1e-9 * static_cast<double>(now - last_path_ns_) >= 1.0 / options_.path_rate) {
    last_path_ns_ = now;
    msg::Path path;
    setStamp(path.header(), now);
    path.header().frame_id(options_.world_frame);
    path.query_id(q.query.query_id());
    for (const ob::State* state : q.planner->bestPath()) {
      msg::Pose pose;
      pose.position(toPoint(statePosition(state)));
      pose.orientation().w(1.0);
      path.poses().push_back(pose);
    }
    path.cost(q.planner->bestCost().value());
    path_pub_->publish(path);
  }
  if (1e-9 * static_cast<double>(now - last_tree_ns_) >= 1.0 / options_.tree_rate) {
    last_tree_ns_ = now;
    msg::PlannerTree tree;
    setStamp(tree.header(), now);
    tree.header().frame_id(options_.world_frame);
    tree.query_id(q.query.query_id());
    tree.root_index(-1);
    tree.best_solution_index(-1);
    const OnlineRRTstar::Node* best = q.planner->bestSolution();
    // Depth-first from the root: a parent always gets its index before its children.
    std::vector<std::pair<const OnlineRRTstar::Node*, int32_t>> stack;
    if (q.planner->root()) stack.emplace_back(q.planner->root(), -1);
    while (!stack.empty()) {
      const auto [node, parent] = stack.back();
      stack.pop_back();
      const auto index = static_cast<int32_t>(tree.nodes().size());
      const Eigen::Vector3d position = statePosition(node->state);
      tree.nodes().push_back(toPoint(position));
      tree.parents().push_back(parent);
      tree.costs().push_back(node->cost.value());
      if (parent < 0) tree.root_index(index);
      if ((position - q.goal).norm() <= q.query.goal_tolerance()) {
        tree.solution_indices().push_back(index);
      }
      if (node == best) tree.best_solution_index(index);
      for (const OnlineRRTstar::Node* child : node->children) stack.emplace_back(child, index);
    }
    tree.iterations(q.earlier_iterations + q.planner->iterations());
    tree_pub_->publish(tree);
  }
}

void PlanningComponent::requestFullMapIfNeeded() {
  if (!full_map_needed_ || !full_client_->serviceReady()) return;
  // Unanswered earlier calls are superseded: any FULL map repairs the replica.
  full_reply_ = full_client_->callAsync(msg::TriggerRequest{});
  AUV_INFO(node_->logger(),
           "map replica at version " << map_sequence_ << " missed an update: asked for a full map");
}

}  // namespace auv::planning

AUV_REGISTER_COMPONENT(auv::planning::PlanningComponent, "planning",
                       "online anytime RRT* (mission/query -> planner/waypoint) on map/update")
