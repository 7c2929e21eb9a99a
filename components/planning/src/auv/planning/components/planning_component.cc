#include "auv/planning/components/planning_component.h"
#include "auv/interfaces/msg_eigen.h"
#include "auv/interfaces/msg_time.h"
#include "auv/interfaces/option_parameters.h"

#include <chrono>
#include <functional>
#include <variant>

#include "auv/mapping/map_replica.h"

namespace auv::planning {

namespace {

Eigen::Vector3d toVector(const msg::Point& p) { return interfaces::toEigen(p); }
using interfaces::toPoint;

void setStamp(msg::Header& header, int64_t ns) { header.stamp(interfaces::toMsgTime(ns)); }

PlanningQuery toPlanningQuery(const msg::PlannerQuery& query) {
  PlanningQuery converted;
  converted.query_id = query.query_id();
  converted.start = toVector(query.start().position());
  converted.goal = toVector(query.goal().position());
  converted.goal_tolerance = query.goal_tolerance();
  converted.time_budget = query.time_budget();
  // PLANNER_OBJECTIVE_DEFAULT is the planner's configured objective: the visibility cost.
  converted.objective = query.objective() == msg::PLANNER_OBJECTIVE_PATH_LENGTH
                            ? PlanningObjective::PATH_LENGTH
                            : PlanningObjective::VISIBILITY_COST;
  converted.expected_distance = query.expected_distance();
  converted.admissible_range = query.admissible_range();
  converted.bounds_min = toVector(query.bounds_min());
  converted.bounds_max = toVector(query.bounds_max());
  if (query.fixed_depth()) converted.fixed_depth = query.depth();
  converted.min_depth = query.min_depth();
  converted.max_depth = query.max_depth();
  converted.min_altitude = query.min_altitude();
  return converted;
}

msg::CancelReason toMsg(CancelReason reason) {
  switch (reason) {
    case CancelReason::ROOT_IN_COLLISION:
      return msg::CANCEL_REASON_ROOT_IN_COLLISION;
    case CancelReason::APPROACH_IN_COLLISION:
      return msg::CANCEL_REASON_APPROACH_IN_COLLISION;
    case CancelReason::QUERY_REPLACED:
      return msg::CANCEL_REASON_QUERY_REPLACED;
    case CancelReason::NO_SOLUTION:
      return msg::CANCEL_REASON_NO_SOLUTION;
    case CancelReason::PLANNER_ERROR:
      return msg::CANCEL_REASON_PLANNER_ERROR;
    case CancelReason::UNKNOWN_QUERY:
      return msg::CANCEL_REASON_UNKNOWN_QUERY;
  }
  return msg::CANCEL_REASON_UNKNOWN;
}

}  // namespace

PlanningComponent::PlanningComponent() = default;

PlanningComponent::~PlanningComponent() { deactivate(); }

const config::OptionTable<PlanningComponent::Options>& PlanningComponent::Options::table() {
  using config::Range;
  using O = Options;
  static const config::OptionTable<O> kTable = {
      {"path_rate", &O::path_rate, "rate of planner/path", "Hz", Range::closed(0.01, 100.0)},
      {"tree_rate", &O::tree_rate, "rate of planner/tree", "Hz", Range::closed(0.01, 100.0)},
      {"full_request_period", &O::full_request_period,
       "period of map/request_full calls while the replica misses an update", "s",
       Range::closed(0.1, 60.0)},
      {"map_id", &O::map_id, "map instance followed on map/update"},
      {"world_frame", &O::world_frame, "frame of published poses (NED)"},
  };
  return kTable;
}

void PlanningComponent::configure(interfaces::Node& node) {
  node_ = &node;
  auto& p = node.parameters();
  auto& o = options_;
  SessionOptions& session = o;
  interfaces::declareOptions(p, "", SessionOptions::table(), session, /*read_only=*/true);
  interfaces::declareOptions(p, "", ClearanceOptions::table(), o.clearance, true);
  interfaces::declareOptions(p, "", Options::table(), o, true);
  session_ = std::make_unique<PlanningSession>(o);  // checks the options
  replica_ = std::make_unique<mapping::MapReplica>(o.map_id, o.map_resolution);

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
  session_.reset();  // with the query's tree
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
    applyInbox();
    publishOutbox();
    if (session_->planSlice(vehiclePosition(), now())) ++slices_;
    publishOutbox();
    session_->finishSlice(now());  // the time after the slice: the budget counts its length
    publishOutbox();
    publishViews();
    planning = session_->growing();
  }
}

void PlanningComponent::applyInbox() {
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
  if (query) {
    const PlanningQuery converted = toPlanningQuery(*query);
    if (session_->startQuery(converted, replica_->tree(), vehiclePosition(), now())) {
      AUV_INFO(node_->logger(), "planning query " << converted.query_id);
    }
  }
  for (const auto& request : requests) {
    WaypointRequest converted;
    converted.query_id = request.query_id();
    converted.reached_waypoint_id = request.reached_waypoint_id();
    session_->onWaypointRequest(converted, now());
  }
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
    session_->onFullMap(replica_->tree(), replica_->sequence());
  } else {
    session_->onMapIncrement(toVector(update.changed_min()), toVector(update.changed_max()),
                             replica_->sequence());
  }
}

void PlanningComponent::publishOutbox() {
  PlanningSession::Outbox outbox = session_->takeOutbox();
  for (const std::string& warning : outbox.warnings) AUV_WARN(node_->logger(), warning);
  for (const auto& message : outbox.messages) {
    if (const auto* waypoint = std::get_if<PlannedWaypoint>(&message)) {
      // A repeat is the message sent before (its stamp included): the active waypoint is
      // always the last one sent, as a new query or a restart clears it.
      if (!waypoint->repeat || last_waypoint_.waypoint_id() != waypoint->waypoint_id) {
        msg::Waypoint& w = last_waypoint_;
        w = msg::Waypoint();
        setStamp(w.header(), node_->clock().nowNs());
        w.header().frame_id(options_.world_frame);
        w.waypoint_id(waypoint->waypoint_id);
        w.query_id(waypoint->query_id);
        w.position(toPoint(waypoint->position));
        w.heading(waypoint->heading);
        w.speed(waypoint->speed);
        w.tolerance(waypoint->tolerance);
        w.is_final(waypoint->is_final);
      }
      waypoint_pub_->publish(last_waypoint_);
      continue;
    }
    const auto& cancel = std::get<WaypointCancel>(message);
    msg::WaypointCancel c;
    setStamp(c.header(), node_->clock().nowNs());
    c.waypoint_id(cancel.waypoint_id);
    c.query_id(cancel.query_id);
    c.reason(toMsg(cancel.reason));
    c.reason_text(cancel.text);
    cancel_pub_->publish(c);
    AUV_WARN(node_->logger(), "cancelled waypoint " << cancel.waypoint_id << ": " << cancel.text);
  }
}

double PlanningComponent::now() const { return node_->clock().nowSeconds(); }

void PlanningComponent::publishViews() {
  if (!session_->hasQuery()) return;
  const int64_t now_ns = node_->clock().nowNs();
  if (1e-9 * static_cast<double>(now_ns - last_path_ns_) >= 1.0 / options_.path_rate) {
    last_path_ns_ = now_ns;
    const PathSnapshot snapshot = session_->path();
    msg::Path path;
    setStamp(path.header(), now_ns);
    path.header().frame_id(options_.world_frame);
    path.query_id(session_->queryId());
    for (const Eigen::Vector3d& position : snapshot.positions) {
      msg::Pose pose;
      pose.position(toPoint(position));
      pose.orientation().w(1.0);
      path.poses().push_back(pose);
    }
    path.cost(snapshot.cost);
    path_pub_->publish(path);
  }
  if (1e-9 * static_cast<double>(now_ns - last_tree_ns_) >= 1.0 / options_.tree_rate) {
    last_tree_ns_ = now_ns;
    const TreeSnapshot snapshot = session_->tree();
    msg::PlannerTree tree;
    setStamp(tree.header(), now_ns);
    tree.header().frame_id(options_.world_frame);
    tree.query_id(session_->queryId());
    for (const Eigen::Vector3d& node : snapshot.nodes) tree.nodes().push_back(toPoint(node));
    tree.parents(snapshot.parents);
    tree.costs(snapshot.costs);
    tree.root_index(snapshot.root_index);
    tree.best_solution_index(snapshot.best_solution_index);
    tree.solution_indices(snapshot.solution_indices);
    tree.iterations(snapshot.iterations);
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
