#include "auv/mission/components/mission_component.h"

#include <cmath>
#include <filesystem>

#include "auv/config/state_file.h"
#include "auv/interfaces/msg_time.h"
#include "auv/interfaces/option_parameters.h"

namespace auv::mission {
namespace {

double yawOf(const msg::Quaternion& q) {
  return std::atan2(2.0 * (q.w() * q.z() + q.x() * q.y()),
                    1.0 - 2.0 * (q.y() * q.y() + q.z() * q.z()));
}

template <class T>
std::function<void(const T&)> bind(void (MissionComponent::*method)(const T&),
                                   MissionComponent* self) {
  return [self, method](const T& message) { (self->*method)(message); };
}

}  // namespace

const config::OptionTable<MissionComponent::Options>& MissionComponent::Options::table() {
  using config::Range;
  using O = Options;
  static const config::OptionTable<O> kTable = {
      {"tick_rate", &O::tick_rate, "readiness and staleness checks per second", "Hz",
       Range::closed(1.0, 1000.0)},
      {"status_rate", &O::status_rate,
       "periodic mission/status messages per second (also sent on every change)", "Hz",
       Range::closed(0.01, 100.0)},
      {"map_resolution", &O::map_resolution, "leaf size of the map on map/update", "m",
       Range::closed(0.01, 10.0)},
      {"map_id", &O::map_id, "OctomapUpdate.map_id followed"},
      {"mission_file", &O::mission_file,
       "mission YAML loaded at configure (started on activate when autostart)"},
      {"autostart", &O::autostart, "start mission_file when the component activates"},
      {"log_dir", &O::log_dir,
       "folder of the mission log read by `auv mission report` and of progress.yaml, from "
       "which a handler restarted within the same launch resumes the mission (empty: neither)"},
  };
  return kTable;
}

void MissionComponent::configure(interfaces::Node& node) {
  node_ = &node;
  auto& p = node.parameters();
  auto& o = options_;
  auto& e = o.executive;
  // Not read-only, as before, although no callback applies a change to a running executive.
  interfaces::declareOptions(p, "", ExecutiveOptions::table(), e, /*read_only=*/false);
  interfaces::declareOptions(p, "", MissionLimits::table(), o.limits, /*read_only=*/false);
  interfaces::declareOptions(p, "", Options::table(), o, /*read_only=*/true);
  executive_ = std::make_unique<MissionExecutive>(e);                               // check()s
  if (!o.mission_file.empty()) configured_plan_ = loadMissionFile(o.mission_file);  // names it
  if (o.autostart && !configured_plan_) {
    throw std::invalid_argument("parameter autostart: true needs a mission_file");
  }
  map_ = std::make_unique<mapping::MapReplica>(o.map_id, o.map_resolution);
  loadProgress();

  query_pub_ = node.createPublisher<msg::PlannerQuery>("mission/query", interfaces::commandQos());
  request_pub_ = node.createPublisher<msg::WaypointRequest>("planner/waypoint_request",
                                                            interfaces::commandQos());
  command_pub_ =
      node.createPublisher<msg::ControllerCommand>("control/waypoint", interfaces::commandQos());
  status_pub_ =
      node.createPublisher<msg::MissionStatus>("mission/status", interfaces::latchedStateQos());
  // Best effort: the newest estimate is what counts. A reliable reader delivers in order and
  // held newer estimates back while a lost one was repaired: at 6x real time a 0.2-0.4 s wall
  // repair on a loaded machine read as 1.2-2.5 s of stale navigation and aborted missions.
  odometry_sub_ = node.createSubscription<msg::Odometry>(
      "nav/odometry", interfaces::sensorDataQos(), bind(&MissionComponent::onOdometry, this),
      interfaces::SubscriptionOptions{interfaces::CallbackThread::MIDDLEWARE});
  controller_sub_ = node.createSubscription<msg::ControllerStatus>(
      "control/status", interfaces::stateQos(),
      std::function<void(const msg::ControllerStatus&)>([this](const msg::ControllerStatus& s) {
        executive_->onControllerStatus(s, now());
        flush("controller");
      }));
  waypoint_sub_ = node.createSubscription<msg::Waypoint>(
      "planner/waypoint", interfaces::commandQos(),
      std::function<void(const msg::Waypoint&)>([this](const msg::Waypoint& w) {
        if (log_ && executive_->running()) log_->waypoint(now(), w);
        executive_->onWaypoint(w, now());
        flush("waypoint",
              "waypoint " + std::to_string(w.waypoint_id()) + (w.is_final() ? " (final)" : ""));
      }));
  cancel_sub_ = node.createSubscription<msg::WaypointCancel>(
      "planner/cancel", interfaces::commandQos(),
      std::function<void(const msg::WaypointCancel&)>([this](const msg::WaypointCancel& c) {
        executive_->onCancel(c, now());
        flush("cancel", "waypoint " + std::to_string(c.waypoint_id()) + ": " + c.reason_text());
      }));
  map_sub_ = node.createSubscription<msg::OctomapUpdate>(
      "map/update", interfaces::mapQos(),
      std::function<void(const msg::OctomapUpdate&)>([this](const msg::OctomapUpdate& update) {
        if (map_->apply(update) == mapping::MapReplica::Outcome::REJECTED) {
          AUV_WARN(node_->logger(), "map update "
                                        << update.sequence_number()
                                        << " not used for goal checks: " << map_->error());
        }
      }));
  path_sub_ = node.createSubscription<msg::Path>(
      "planner/path", interfaces::viewingQos(),
      std::function<void(const msg::Path&)>([this](const msg::Path& path) {
        if (log_ && executive_->running()) log_->path(now(), path);
      }));
  tree_sub_ = node.createSubscription<msg::PlannerTree>(
      "planner/tree", interfaces::viewingQos(),
      std::function<void(const msg::PlannerTree&)>([this](const msg::PlannerTree& tree) {
        if (log_ && executive_->running()) log_->tree(tree);
      }));
  start_service_ = node.createService<msg::StartMissionRequest, msg::StartMissionReply>(
      "mission/start", [this](const msg::StartMissionRequest& request,
                              msg::StartMissionReply& reply) { onStart(request, reply); });
  abort_service_ = node.createService<msg::TriggerRequest, msg::TriggerReply>(
      "mission/abort", [this](const msg::TriggerRequest& request, msg::TriggerReply& reply) {
        onAbort(request, reply);
      });
}

void MissionComponent::loadProgress() {
  if (options_.log_dir.empty()) return;
  const std::filesystem::path file = std::filesystem::path(options_.log_dir) / "progress.yaml";
  try {
    std::optional<MissionProgress> progress = readProgress(file);
    if (!progress || !progress->running()) return;
    if (progress->launch_id.empty() || progress->launch_id != config::launchId()) {
      AUV_INFO(node_->logger(), file.string() << ": mission '" << progress->mission_id
                                              << "' of another launch, not resumed");
      return;
    }
    resumable_ = std::move(progress);
    missions_started_ = 1;  // resumed, not started again by autostart
    AUV_WARN(node_->logger(), "restarted during mission '" << resumable_->mission_id << "' (query "
                                                           << resumable_->query_index + 1 << "/"
                                                           << resumable_->plan.queries.size()
                                                           << "): resuming it when the clock runs");
  } catch (const std::exception& error) {
    AUV_ERROR(node_->logger(), "not resuming: " << error.what());
  }
}

void MissionComponent::resumeMission() {
  const MissionProgress progress = std::move(*resumable_);
  resumable_.reset();
  feedOdometry();
  std::string why;
  if (!executive_->resume(progress, now(), &why)) {
    AUV_ERROR(node_->logger(), "mission '" << progress.mission_id << "' not resumed: " << why);
    return;
  }
  plan_name_ = progress.plan.name;
  try {
    log_ = std::make_unique<MissionLog>(options_.log_dir, progress.plan, /*resume=*/true);
  } catch (const std::exception& error) {
    AUV_ERROR(node_->logger(), "mission log disabled: " << error.what());
  }
  flush("resume");
}

void MissionComponent::saveProgress() {
  if (options_.log_dir.empty()) return;
  MissionProgress progress = executive_->progress();
  if (progress.mission_id.empty()) return;  // no mission yet
  progress.launch_id = config::launchId();
  progress.plan.name = plan_name_;
  try {
    writeProgress(std::filesystem::path(options_.log_dir) / "progress.yaml", progress);
    progress_error_.clear();
  } catch (const std::exception& error) {
    if (progress_error_ != error.what()) {  // a full disk would log every status change
      progress_error_ = error.what();
      AUV_ERROR(node_->logger(),
                "mission progress not saved (a restart could not resume): " << error.what());
    }
  }
}

void MissionComponent::activate() {
  tick_timer_ = node_->createTimer(1.0 / options_.tick_rate, [this] { tick(); });
  status_timer_ = node_->createTimer(1.0 / options_.status_rate, [this] { publishStatus(); });
  publishStatus();
  if (options_.autostart) {
    // Started from the first tick, once the clock runs (simulation time may not have begun).
    AUV_INFO(node_->logger(), "mission " << options_.mission_file << " starts when the clock runs");
  }
}

void MissionComponent::deactivate() {
  if (executive_ && executive_->running()) {
    executive_->abort("mission component deactivated", now());
    flush("abort", "deactivated");
  }
  if (tick_timer_) tick_timer_->cancel();
  if (status_timer_) status_timer_->cancel();
  tick_timer_.reset();
  status_timer_.reset();
}

void MissionComponent::cleanup() {
  start_service_.reset();
  abort_service_.reset();
  odometry_sub_.reset();
  controller_sub_.reset();
  waypoint_sub_.reset();
  cancel_sub_.reset();
  map_sub_.reset();
  path_sub_.reset();
  tree_sub_.reset();
  query_pub_.reset();
  request_pub_.reset();
  command_pub_.reset();
  status_pub_.reset();
  log_.reset();
}

double MissionComponent::now() const { return node_->clock().nowSeconds(); }

std::string MissionComponent::startMission(const std::string& requested_id, const MissionPlan& plan,
                                           const std::string& source) {
  feedOdometry();  // the checks use the newest position
  const auto& position = executive_->vehiclePosition();
  try {
    for (const MissionQuery& query : plan.queries) {
      if (query.fixed_depth && !query.depth && !position) {
        throw MissionError(source + ": query '" + query.name +
                           "' plans at the vehicle's depth, but no navigation has arrived yet "
                           "(nav/odometry): give its depth or start again when navigation runs");
      }
    }
    for (const MissionQuery& query : plan.queries) checkQuery(query, source);
    checkAgainstVehicle(plan.queries, map_->sequence() > 0 ? &map_->tree() : nullptr,
                        position ? position->z() : 0.0, options_.limits, source);
  } catch (const MissionError& error) {
    throw interfaces::ServiceError(msg::REPLY_CODE_INVALID_ARGUMENT, error.what());
  }
  const std::string mission_id =
      requested_id.empty() ? plan.name + "-" + std::to_string(++missions_started_) : requested_id;
  std::string why;
  if (!executive_->start(mission_id, plan.queries, now(), &why)) {
    throw interfaces::ServiceError(msg::REPLY_CODE_REJECTED, why);
  }
  plan_name_ = plan.name;
  if (!options_.log_dir.empty()) {
    try {
      log_ = std::make_unique<MissionLog>(options_.log_dir, plan);
    } catch (const std::exception& error) {
      AUV_ERROR(node_->logger(), "mission log disabled: " << error.what());
      log_.reset();
    }
  }
  AUV_INFO(node_->logger(),
           "mission '" << mission_id << "' started: " << plan.queries.size() << " queries");
  flush("start", source);
  return mission_id;
}

void MissionComponent::onStart(const msg::StartMissionRequest& request,
                               msg::StartMissionReply& reply) {
  // mission/status is keyed by the id, and a DDS key string holds at most 255 bytes.
  constexpr std::size_t kMaxIdBytes = 255;
  if (request.mission_id().size() > kMaxIdBytes) {
    throw interfaces::ServiceError(msg::REPLY_CODE_INVALID_ARGUMENT,
                                   "mission_id: at most " + std::to_string(kMaxIdBytes) +
                                       " bytes (it keys mission/status), got " +
                                       std::to_string(request.mission_id().size()));
  }
  MissionPlan plan;
  if (request.queries().empty()) {
    if (!configured_plan_) {
      throw interfaces::ServiceError(msg::REPLY_CODE_INVALID_ARGUMENT,
                                     "no queries given and no mission_file configured");
    }
    plan = *configured_plan_;
  } else {
    plan.name = request.mission_id().empty() ? "mission" : request.mission_id();
    for (std::size_t i = 0; i < request.queries().size(); ++i) {
      plan.queries.push_back(fromPlannerQuery(request.queries()[i], i));
    }
  }
  reply.mission_id(startMission(request.mission_id(), plan, "mission/start"));
}

void MissionComponent::onAbort(const msg::TriggerRequest& request, msg::TriggerReply& reply) {
  const std::string reason =
      "aborted by request" + (request.command().empty() ? "" : " (" + request.command() + ")");
  if (!executive_->abort(reason, now())) {
    throw interfaces::ServiceError(msg::REPLY_CODE_REJECTED, "no mission is running");
  }
  flush("abort", reason);
  reply.message("mission '" + executive_->status().mission_id() +
                "' aborted: " + executive_->status().message());
}

void MissionComponent::onOdometry(const msg::Odometry& odometry) {
  const auto& pose = odometry.pose().pose();
  const Eigen::Vector3d position(pose.position().x(), pose.position().y(), pose.position().z());
  const double yaw = yawOf(pose.orientation());
  if (!position.allFinite() || !std::isfinite(yaw)) return;  // no navigation: staleness decides
  std::lock_guard<std::mutex> lock(odometry_mutex_);
  latest_odometry_.position = position;
  latest_odometry_.yaw = yaw;
  latest_odometry_.arrival = now();
  ++latest_odometry_.count;
}

void MissionComponent::feedOdometry() {
  LatestOdometry latest;
  {
    std::lock_guard<std::mutex> lock(odometry_mutex_);
    latest = latest_odometry_;
  }
  if (latest.count == fed_odometry_count_) return;
  fed_odometry_count_ = latest.count;
  executive_->onOdometry(latest.position, latest.yaw, latest.arrival);
  flush("odometry");
}

void MissionComponent::tick() {
  if (!node_->clock().valid()) return;  // simulation time has not started
  if (resumable_) resumeMission();
  if (options_.autostart && configured_plan_ && missions_started_ == 0) {
    try {
      startMission("", *configured_plan_, options_.mission_file);
    } catch (const std::exception& error) {
      AUV_ERROR(node_->logger(),
                "mission " << options_.mission_file << " refused: " << error.what());
      ++missions_started_;  // refused once, not retried every tick
    }
  }
  feedOdometry();
  executive_->setPlannerPresent(query_pub_->matchedSubscriptions() > 0);
  executive_->tick(now());
  flush("tick");
}

void MissionComponent::flush(const std::string& event, const std::string& detail) {
  MissionExecutive::Outbox out = executive_->takeOutbox();
  for (auto& query : out.queries) {
    query.header().stamp(interfaces::toMsgTime(node_->clock().nowNs()));
    query_pub_->publish(query);
  }
  for (auto& request : out.requests) {
    request.header().stamp(interfaces::toMsgTime(node_->clock().nowNs()));
    request_pub_->publish(request);
  }
  for (auto& command : out.commands) {
    command.header().stamp(interfaces::toMsgTime(node_->clock().nowNs()));
    command_pub_->publish(command);
  }
  if (log_) {
    for (const auto& event : out.events) {  // RECOVERY_START, RECOVERY_REISSUE
      log_->event(now(), event.name, executive_->status(),
                  executive_->vehiclePosition().value_or(Eigen::Vector3d::Constant(std::nan(""))),
                  event.detail);
    }
  }
  for (const auto& event : out.events)
    AUV_WARN(node_->logger(), event.name << ": " << event.detail);
  if (!out.status_changed) return;
  saveProgress();
  const msg::MissionStatus& status = executive_->status();
  if (status.state() != logged_state_) {
    AUV_INFO(node_->logger(), toString(status.state()) << ": " << status.message());
    logged_state_ = status.state();
  }
  if (log_) {
    const Eigen::Vector3d position =
        executive_->vehiclePosition().value_or(Eigen::Vector3d::Constant(std::nan("")));
    log_->event(now(), std::string(toString(status.state())) + "/" + event, status, position,
                status.message() + (detail.empty() ? "" : " | " + detail));
    if (!executive_->running() && status.state() != msg::MISSION_STATE_IDLE) {
      log_->finish(status, map_->sequence() > 0 ? &map_->tree() : nullptr);
      log_.reset();
    }
  }
  publishStatus();
}

void MissionComponent::publishStatus() {
  msg::MissionStatus status = executive_->status();
  status.header().stamp(interfaces::toMsgTime(node_->clock().nowNs()));
  if (status.mission_id().empty()) status.mission_id("none");
  status_pub_->publish(status);
}

}  // namespace auv::mission

AUV_REGISTER_COMPONENT(auv::mission::MissionComponent, "mission",
                       "mission handler: queries -> planner, waypoints -> controller")
