#include "auv/mapping/components/mapping_component.h"
#include "auv/config/state_file.h"
#include "auv/interfaces/msg_eigen.h"
#include "auv/interfaces/msg_time.h"
#include "auv/interfaces/option_parameters.h"
#include "auv/mapping/components/message_conversions.h"

#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace auv::mapping {
using interfaces::toPoint;

const config::OptionTable<MappingComponent::Options>& MappingComponent::Options::table() {
  using config::Range;
  using O = Options;
  static const config::OptionTable<O> kTable = {
      {"update_rate", &O::update_rate, "rate of incremental map updates", "Hz",
       Range::closed(0.01, 100.0)},
      {"full_map_period", &O::full_map_period, "period of full map updates", "s",
       Range::closed(0.1, 3600.0)},
      {"late_joiner_hold", &O::late_joiner_hold,
       "increments held back after a new map reader appears (see header)", "s",
       Range::closed(0.0, 60.0)},
      {"map_id", &O::map_id, "map instance key on map/update"},
      {"world_frame", &O::world_frame, "map and odometry frame (NED)"},
      {"map_directory", &O::map_directory, "directory map/save writes into"},
      {"beam_queue_length", &O::beam_queue_length, "beams kept waiting for newer odometry", "beams",
       Range::closed(0, 100000)},
      {"cloud_queue_length", &O::cloud_queue_length,
       "body-frame point clouds (sonar/scan, dvl/beams) kept waiting for newer odometry", "clouds",
       Range::closed(0, 10000)},
      {"initial_map", &O::initial_map,
       "a .bt map to start from (map/save's format, same resolution), e.g. an earlier "
       "mission's at the site; empty: start empty"},
      {"checkpoint_period", &O::checkpoint_period,
       "how often the changing map is checkpointed to map_directory/checkpoint_<launch>.ot, "
       "which a mapping restarted within the same launch starts from (0: never)",
       "s", Range::closed(0.0, 3600.0)},
      {"align_initial_map", &O::align_initial_map,
       "hold initial_map aside until the vehicle's returns align with it (false: trust it as "
       "it is, in this run's frame)"},
  };
  return kTable;
}

void MappingComponent::configure(interfaces::Node& node) {
  node_ = &node;
  // Meaning, unit and range from the options' own tables: what their check() accepts.
  auto& p = node.parameters();
  interfaces::declareOptions(p, "", MapBuilder::Options::table(), options_.map, true);
  interfaces::declareOptions(p, "", PoseBuffer::Options::table(), options_.poses, true);
  interfaces::declareOptions(p, "", Options::table(), options_, /*read_only=*/true);
  interfaces::declareOptions(p, "prior_", PriorMapAlignment::Options::table(), options_.prior,
                             /*read_only=*/true);
  interfaces::declareOptions(p, "navigation_", NavigationJumpDetector::Options::table(),
                             options_.navigation, /*read_only=*/true);
  options_.prior.check();
  jumps_ = std::make_unique<NavigationJumpDetector>(options_.navigation);

  builder_ = std::make_unique<MapBuilder>(options_.map);  // checks cross-field constraints
  // A restart resumes this launch's map; a prior map to align is aligned again (its cells
  // may be in the checkpoint already: the second insertion only meets the clamping bounds).
  if (!loadCheckpoint() || options_.align_initial_map) loadInitialMap();
  builder_->enableChangeTracking(true);
  poses_ = std::make_unique<PoseBuffer>(options_.poses);

  update_pub_ = node.createPublisher<msg::OctomapUpdate>("map/update", interfaces::mapQos());
  odometry_sub_ = node.createSubscription<msg::Odometry>(
      "nav/odometry", interfaces::stateQos(),
      std::function<void(const msg::Odometry&)>([this](const msg::Odometry& o) { onOdometry(o); }));
  beam_sub_ = node.createSubscription<msg::SonarBeam>(
      "sonar/beam", interfaces::sensorDataQos(),
      std::function<void(const msg::SonarBeam&)>([this](const msg::SonarBeam& b) { onBeam(b); }));
  cloud_sub_ = node.createSubscription<msg::PointCloud>(
      "sonar/scan", interfaces::sensorDataQos(),
      std::function<void(const msg::PointCloud&)>(
          [this](const msg::PointCloud& c) { onCloud(c); }));
  // The DVL's beams are bottom returns: rays like the multibeam's, through the same path.
  dvl_beams_sub_ = node.createSubscription<msg::PointCloud>(
      "dvl/beams", interfaces::sensorDataQos(),
      std::function<void(const msg::PointCloud&)>(
          [this](const msg::PointCloud& c) { onCloud(c); }));

  save_srv_ = node.createService<msg::SaveMapRequest, msg::SaveMapReply>(
      "map/save", [this](const msg::SaveMapRequest& request, msg::SaveMapReply& reply) {
        onSave(request, reply);
      });
  clear_srv_ = node.createService<msg::TriggerRequest, msg::TriggerReply>(
      "map/clear", [this](const msg::TriggerRequest&, msg::TriggerReply& reply) {
        const std::size_t leaves = builder_->tree().getNumLeafNodes();
        builder_->clear();
        builder_->takeSnapshot();
        full_due_ = true;  // an increment cannot express deletions
        map_replaced_ = true;
        reply.message("cleared " + std::to_string(leaves) + " leaves");
      });
  full_srv_ = node.createService<msg::TriggerRequest, msg::TriggerReply>(
      "map/request_full", [this](const msg::TriggerRequest&, msg::TriggerReply& reply) {
        full_due_ = true;
        reply.message("full map on the next update");
      });
}

void MappingComponent::loadInitialMap() {
  if (options_.initial_map.empty()) return;
  try {
    if (!options_.align_initial_map) {
      builder_->load(options_.initial_map);
      AUV_INFO(node_->logger(), "started from " << options_.initial_map << " ("
                                                << builder_->tree().getNumLeafNodes()
                                                << " leaves)");
      return;
    }
    MapBuilder loader(options_.map);  // same settings and checks as the map itself
    loader.load(options_.initial_map);
    aligner_ = std::make_unique<PriorMapAlignment>(std::make_unique<octomap::OcTree>(loader.tree()),
                                                   options_.prior);
  } catch (const std::runtime_error& error) {
    throw interfaces::ParameterError("parameter 'initial_map': " + std::string(error.what()));
  }
  prior_alignment_ = aligner_->result();
  recordAlignment(*prior_alignment_);  // the record says from the start that it is held aside
  AUV_INFO(node_->logger(),
           "holding " << options_.initial_map << " (" << aligner_->prior().getNumLeafNodes()
                      << " leaves) aside until the vehicle's returns align with it; the map "
                         "holds only new sonar evidence until then");
}

bool MappingComponent::loadCheckpoint() {
  const std::string launch = config::launchId();
  if (launch.empty() || options_.checkpoint_period <= 0.0) return false;
  checkpoint_path_ =
      std::filesystem::path(options_.map_directory) / ("checkpoint_" + launch + ".ot");
  const std::filesystem::path& path = checkpoint_path_;
  std::error_code error;
  if (!std::filesystem::exists(path, error)) return false;
  try {
    builder_->load(path.string());
  } catch (const std::runtime_error& failure) {
    // A damaged checkpoint must not keep the vehicle without a map: start as a new launch.
    AUV_ERROR(node_->logger(), "not resuming the map: " << failure.what());
    return false;
  }
  AUV_WARN(node_->logger(), "restarted within the launch: resumed the map from "
                                << path.string() << " (" << builder_->tree().getNumLeafNodes()
                                << " leaves)");
  return true;
}

void MappingComponent::checkpointIfDue(int64_t now_ns) {
  const std::filesystem::path& path = checkpoint_path_;
  if (path.empty() || builder_->version() == checkpoint_version_) return;
  if (1e-9 * static_cast<double>(now_ns - last_checkpoint_ns_) < options_.checkpoint_period) return;
  last_checkpoint_ns_ = now_ns;
  try {
    config::writeFileAtomically(path, builder_->fullWithProbabilities());
    checkpoint_version_ = builder_->version();
    checkpoint_error_.clear();
  } catch (const std::runtime_error& failure) {
    if (checkpoint_error_ != failure.what()) {  // a full disk would log every period
      checkpoint_error_ = failure.what();
      AUV_ERROR(node_->logger(),
                "map checkpoint not written (a restart would start empty): " << failure.what());
    }
  }
}

void MappingComponent::collectReturn(const Eigen::Vector3d& point) {
  if (aligner_) aligner_->addReturn(point);
}

void MappingComponent::attemptAlignment() {
  const AlignmentResult& result = aligner_->attempt();
  prior_alignment_ = result;
  std::ostringstream transform;
  transform.precision(4);
  transform << "x " << result.x_m << " m, y " << result.y_m << " m, z " << result.z_m << " m, yaw "
            << result.yaw_rad * 180.0 / M_PI << " deg";
  if (result.state == AlignmentState::ALIGNED) {
    // The prior, moved into this run's frame, fills what the vehicle has not seen itself.
    const InsertStats stats = builder_->insertPrior(aligner_->prior(), result.navigation_T_prior,
                                                    options_.prior.log_odds_scale);
    full_due_ = true;
    AUV_INFO(node_->logger(), "prior map aligned after "
                                  << result.points_collected << " returns: prior -> "
                                  << options_.world_frame << " " << transform.str() << "; "
                                  << result.reason << "; added " << stats.occupied_cells
                                  << " occupied and " << stats.free_cells << " free cells");
  } else if (result.finished) {
    AUV_WARN(node_->logger(),
             "prior map " << toString(result.state) << ", not used: " << result.reason);
  } else {
    AUV_INFO(node_->logger(), "prior map alignment attempt " << result.attempts << ": "
                                                             << toString(result.state) << ", "
                                                             << result.reason);
  }
  recordAlignment(result);
  if (result.finished) aligner_.reset();  // the prior is in the map, or unused
}

void MappingComponent::recordAlignment(const AlignmentResult& result) const {
  const std::filesystem::path path =
      std::filesystem::path(options_.map_directory) / "prior_alignment.json";
  std::error_code error;
  std::filesystem::create_directories(path.parent_path(), error);
  const auto quoted = [](const std::string& text) {
    std::string out = "\"";
    for (char c : text) {
      if (c == '"' || c == '\\') out += '\\';
      out += c;
    }
    return out + "\"";
  };
  const std::time_t now = std::time(nullptr);
  char utc[32];
  std::strftime(utc, sizeof(utc), "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  std::ofstream file(path);
  file.precision(9);
  file << "{\n  \"state\": " << quoted(toString(result.state))
       << ",\n  \"finished\": " << (result.finished ? "true" : "false")
       << ",\n  \"initial_map\": " << quoted(options_.initial_map)
       << ",\n  \"frames\": {\"from\": \"prior\", \"to\": " << quoted(options_.world_frame)
       << "},\n  \"transform\": {\"x\": " << result.x_m << ", \"y\": " << result.y_m
       << ", \"z\": " << result.z_m << ", \"yaw_rad\": " << result.yaw_rad
       << ", \"yaw_deg\": " << result.yaw_rad * 180.0 / M_PI
       << "},\n  \"inlier_fraction\": " << result.inlier_fraction
       << ",\n  \"rms_m\": " << result.rms_m
       << ",\n  \"ambiguity_ratio\": " << result.ambiguity_ratio
       << ",\n  \"constraint\": " << result.constraint
       << ",\n  \"points_used\": " << result.points_used
       << ",\n  \"points_collected\": " << result.points_collected
       << ",\n  \"attempts\": " << result.attempts << ",\n  \"reason\": " << quoted(result.reason)
       << ",\n  \"stamp\": " << 1e-9 * static_cast<double>(newest_stamp_ns_)
       << ",\n  \"time\": " << quoted(utc) << "\n}\n";
  file.close();
  if (!file) AUV_WARN(node_->logger(), "cannot write " << path.string());
}

void MappingComponent::onSave(const msg::SaveMapRequest& request, msg::SaveMapReply& reply) {
  const std::filesystem::path relative(request.file_path());
  const bool probabilities = request.encoding() == msg::OCTOMAP_ENCODING_FULL;
  std::filesystem::path name =
      relative.empty() ? std::filesystem::path("map_" + std::to_string(sequence_number_) +
                                               (probabilities ? ".ot" : ".bt"))
                       : relative;
  for (const auto& part : name) {
    if (part == "..") throw std::invalid_argument("file_path must not contain '..'");
  }
  if (name.is_absolute()) throw std::invalid_argument("file_path must be relative");
  const std::filesystem::path full = std::filesystem::path(options_.map_directory) / name;
  std::error_code error;
  if (full.has_parent_path()) std::filesystem::create_directories(full.parent_path(), error);
  std::ofstream file(full, std::ios::binary);
  const std::string data =
      probabilities ? builder_->fullWithProbabilities() : builder_->fullBinary();
  file.write(data.data(), static_cast<std::streamsize>(data.size()));
  file.close();
  if (!file) {
    throw interfaces::ServiceError(msg::REPLY_CODE_IO_ERROR, "cannot write " + full.string());
  }
  reply.file_path(name.string());
  reply.size_bytes(data.size());
  reply.sequence_number(sequence_number_);
  AUV_INFO(node_->logger(), "saved map to " << full.string() << " (" << data.size() << " bytes)");
}

void MappingComponent::activate() {
  full_due_ = true;
  timer_ = node_->createTimer(1.0 / options_.update_rate, [this] { tick(); });
  AUV_INFO(node_->logger(), "mapping at " << options_.map.resolution << " m, updates at "
                                          << options_.update_rate << " Hz, full every "
                                          << options_.full_map_period << " s");
}

void MappingComponent::deactivate() {
  if (timer_) timer_->cancel();
  timer_.reset();
}

void MappingComponent::cleanup() {
  beam_sub_.reset();
  cloud_sub_.reset();
  dvl_beams_sub_.reset();
  odometry_sub_.reset();
  update_pub_.reset();
  save_srv_.reset();
  clear_srv_.reset();
  full_srv_.reset();
}

void MappingComponent::onOdometry(const msg::Odometry& odometry) {
  const StampedPose pose = toStampedPose(odometry);
  if (const auto jump = jumps_->add(pose.stamp_ns, pose.position)) {
    followNavigationJump(*jump, pose.stamp_ns);
  }
  poses_->add(pose);
  // Beams that arrived before the odometry covering them.
  while (!waiting_beams_.empty() && tryInsertBeam(waiting_beams_.front())) {
    waiting_beams_.pop_front();
  }
  while (!waiting_clouds_.empty() && tryInsertCloud(waiting_clouds_.front())) {
    waiting_clouds_.pop_front();
  }
}

void MappingComponent::followNavigationJump(const Eigen::Vector3d& jump, int64_t stamp_ns) {
  // The world did not move: the estimate did. What was seen before now lies `jump` away from
  // where the same surfaces are seen from here on, so the map moves with the estimate. Poses
  // before the jump must not be interpolated across it: measurements stamped before it that
  // still wait for odometry are dropped (BEFORE_START).
  const octomap::OcTree before(builder_->tree());
  builder_->clear();
  const InsertStats stats = builder_->insertPrior(
      before, Eigen::Isometry3d(Eigen::Translation3d(jump)), options_.navigation.log_odds_scale);
  poses_->clear();
  ++navigation_jumps_;
  full_due_ = true;  // an increment cannot express the move
  map_replaced_ = true;
  if (aligner_) {
    // Returns collected for a prior map's alignment are in the frame before the jump.
    aligner_ = std::make_unique<PriorMapAlignment>(
        std::make_unique<octomap::OcTree>(aligner_->prior()), options_.prior);
  }
  AUV_WARN(node_->logger(), "navigation jumped by ("
                                << jump.x() << ", " << jump.y() << ", " << jump.z() << ") m at "
                                << 1e-9 * static_cast<double>(stamp_ns)
                                << " s: the map moved with it (" << stats.occupied_cells
                                << " occupied cells)");
}

void MappingComponent::onBeam(const msg::SonarBeam& message) {
  PendingBeam beam{interfaces::toNanoseconds(message.header().stamp()), toGeometry(message),
                   toIsometry(message.mounting())};
  if (!waiting_beams_.empty() || !tryInsertBeam(beam)) {  // keep beams in stamp order
    waiting_beams_.push_back(std::move(beam));
    while (static_cast<int64_t>(waiting_beams_.size()) > options_.beam_queue_length) {
      waiting_beams_.pop_front();
      ++beams_dropped_;
    }
  }
}

bool MappingComponent::tryInsertBeam(const PendingBeam& beam) {
  PoseLookupStatus status;
  const auto pose = poses_->lookUp(beam.stamp_ns, &status);
  if (!pose) {
    if (status == PoseLookupStatus::AFTER_END || status == PoseLookupStatus::EMPTY) return false;
    ++beams_dropped_;  // can never be placed
    AUV_DEBUG(node_->logger(), "dropped beam: " << toString(status));
    return true;
  }
  const Eigen::Isometry3d world_T_sensor = toIsometry(*pose) * beam.mounting;
  builder_->insertBeam(beam.geometry, world_T_sensor);
  if (aligner_) {
    if (const auto point = MapBuilder::returnPoint(beam.geometry, world_T_sensor)) {
      collectReturn(*point);
    }
  }
  ++beams_inserted_;
  newest_stamp_ns_ = std::max(newest_stamp_ns_, beam.stamp_ns);
  return true;
}

void MappingComponent::onCloud(const msg::PointCloud& cloud) {
  const int64_t stamp_ns = interfaces::toNanoseconds(cloud.header().stamp());
  std::vector<Eigen::Vector3d> points;
  points.reserve(cloud.points().size());
  for (const auto& point : cloud.points()) points.emplace_back(point.x(), point.y(), point.z());
  const Eigen::Vector3d origin = toIsometry(cloud.sensor_origin()).translation();
  // Points in the world frame are used as they are; any other frame is taken as the body
  // frame and placed with the odometry pose at the cloud's stamp, waiting for it like beams.
  if (cloud.header().frame_id() == options_.world_frame) {
    insertWorldCloud(stamp_ns, points, origin, cloud.max_range());
    return;
  }
  PendingCloud pending{stamp_ns, std::move(points), origin, cloud.max_range()};
  if (!waiting_clouds_.empty() || !tryInsertCloud(pending)) {  // keep clouds in stamp order
    waiting_clouds_.push_back(std::move(pending));
    while (static_cast<int64_t>(waiting_clouds_.size()) > options_.cloud_queue_length) {
      waiting_clouds_.pop_front();
      ++clouds_dropped_;
    }
  }
}

bool MappingComponent::tryInsertCloud(const PendingCloud& cloud) {
  PoseLookupStatus status;
  const auto pose = poses_->lookUp(cloud.stamp_ns, &status);
  if (!pose) {
    if (status == PoseLookupStatus::AFTER_END || status == PoseLookupStatus::EMPTY) return false;
    ++clouds_dropped_;  // can never be placed
    AUV_DEBUG(node_->logger(), "dropped cloud: " << toString(status));
    return true;
  }
  const Eigen::Isometry3d world_T_body = toIsometry(*pose);
  std::vector<Eigen::Vector3d> points;
  points.reserve(cloud.points.size());
  for (const Eigen::Vector3d& point : cloud.points) points.push_back(world_T_body * point);
  insertWorldCloud(cloud.stamp_ns, points, world_T_body * cloud.origin, cloud.max_range);
  return true;
}

void MappingComponent::insertWorldCloud(int64_t stamp_ns,
                                        const std::vector<Eigen::Vector3d>& points,
                                        const Eigen::Vector3d& origin, double max_range) {
  builder_->insertCloud(points, origin, max_range);
  if (aligner_) {
    for (const Eigen::Vector3d& point : points) {
      if (MapBuilder::isReturn(point, origin, max_range)) collectReturn(point);
    }
  }
  ++clouds_inserted_;
  newest_stamp_ns_ = std::max(newest_stamp_ns_, stamp_ns);
}

void MappingComponent::tick() {
  const int readers = update_pub_->matchedSubscriptions();
  const int64_t now_ns = node_->clock().nowNs();
  if (readers > matched_readers_) {
    // A late joiner needs the whole map. The writer may see the reader before the reader sees
    // the writer; the reader then gets only the newest samples of the transient-local
    // history, so keep the FULL the newest sample for late_joiner_hold.
    full_due_ = true;
    hold_increments_until_ns_ = now_ns + static_cast<int64_t>(options_.late_joiner_hold * 1e9);
  }
  matched_readers_ = readers;
  if (aligner_ && aligner_->attemptDue()) attemptAlignment();  // may make a FULL due
  if (1e-9 * static_cast<double>(now_ns - last_full_ns_) >= options_.full_map_period) {
    full_due_ = true;
  }
  if (full_due_) {
    publishFull();
    full_due_ = false;
    last_full_ns_ = now_ns;
  } else if (builder_->pendingChangeCount() > 0 && now_ns >= hold_increments_until_ns_) {
    publishIncrement();
  }
  checkpointIfDue(now_ns);
  // In-process readers: a copy of the whole tree, so only if one asked (map_builder.h).
  builder_->refreshSnapshot();
}

void MappingComponent::fillCommon(msg::OctomapUpdate& update) const {
  update.header().stamp(interfaces::toMsgTime(version_stamp_ns_));
  update.header().frame_id(options_.world_frame);
  update.map_id(options_.map_id);
  update.tree_type(builder_->tree().getTreeType());
  update.resolution(builder_->tree().getResolution());
  // Log-odds are needed for increments to reproduce the map exactly: .ot streams.
  update.encoding(msg::OCTOMAP_ENCODING_FULL);
}

void MappingComponent::publishFull() {
  // A FULL map is the version of the update before it: readers that followed every increment
  // hold it already and skip it (map_replica.h) instead of parsing it and rebuilding what
  // depends on the map. So pending changes go out as an increment first. A cleared map is a
  // new map, and a new version.
  if (map_replaced_) {
    builder_->takeDiff();
    ++sequence_number_;
    version_stamp_ns_ = newest_stamp_ns_;
    map_replaced_ = false;
  } else if (builder_->pendingChangeCount() > 0) {
    publishIncrement();
  }
  msg::OctomapUpdate update;
  fillCommon(update);
  update.sequence_number(sequence_number_);
  update.base_sequence(0);
  update.kind(msg::OCTOMAP_UPDATE_FULL);
  double x0, y0, z0, x1, y1, z1;
  builder_->tree().getMetricMin(x0, y0, z0);
  builder_->tree().getMetricMax(x1, y1, z1);
  if (builder_->tree().size() == 0) {
    update.changed_min(toPoint(Eigen::Vector3d::Constant(1.0)));
    update.changed_max(toPoint(Eigen::Vector3d::Constant(-1.0)));
  } else {
    update.changed_min(toPoint({x0, y0, z0}));
    update.changed_max(toPoint({x1, y1, z1}));
  }
  const std::string data = builder_->fullWithProbabilities();
  update.data(std::vector<uint8_t>(data.begin(), data.end()));
  update_pub_->publish(update);
}

void MappingComponent::publishIncrement() {
  const MapBuilder::Diff diff = builder_->takeDiff();
  version_stamp_ns_ = newest_stamp_ns_;
  msg::OctomapUpdate update;
  fillCommon(update);
  update.base_sequence(sequence_number_);
  update.sequence_number(++sequence_number_);
  update.kind(msg::OCTOMAP_UPDATE_INCREMENTAL);
  update.changed_min(toPoint(diff.changed_min));
  update.changed_max(toPoint(diff.changed_max));
  update.data(std::vector<uint8_t>(diff.data.begin(), diff.data.end()));
  update_pub_->publish(update);
}

}  // namespace auv::mapping

AUV_REGISTER_COMPONENT(auv::mapping::MappingComponent, "mapping",
                       "OctoMap occupancy map from sonar/beam + nav/odometry on map/update")
