#include "auv/sim/components/simulator_component.h"
#include "auv/sim/world/mission_export.h"

#include <yaml-cpp/yaml.h>

#include <chrono>
#include <ctime>
#include <filesystem>
#include <fstream>

#include "auv/interfaces/option_parameters.h"
#include "auv/sim/components/message_conversion.h"
#include "auv/sim/worldgen/world_generator.h"

namespace auv::sim {
namespace {

namespace fs = std::filesystem;

std::string joinWorldNames() {
  std::string names;
  for (const std::string& w : availableWorlds()) names += (names.empty() ? "" : ", ") + w;
  return names;
}

// ground_truth/clearance.csv: rows per simulated second, and the distance they are capped at.
constexpr double kClearanceRate = 5.0;
constexpr double kClearanceCap = 5.0;

std::string timestampForFolder() {
  const std::time_t now = std::time(nullptr);
  char text[32];
  std::strftime(text, sizeof(text), "%Y%m%d-%H%M%S", std::localtime(&now));
  return text;
}

// The scenario as used, next to the ground truth, with the mesh path made absolute so that
// `auv sim render <run>` finds the world from anywhere.
void writeRunScenario(const Scenario& scenario, const std::string& run_dir) {
  YAML::Node root = YAML::Clone(scenario.root.node());
  root["world"]["mesh"] = scenario.mesh_path;
  const fs::path path = fs::path(run_dir) / "scenario.yaml";
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path.string() + ": cannot write the file");
  out << "# Scenario used by this run (written by the simulator; world.mesh made absolute).\n"
      << root << "\n";
}

}  // namespace

const config::OptionTable<SimulatorComponent::Options>& SimulatorComponent::Options::table() {
  using config::Range;
  using O = Options;
  static const config::OptionTable<O> kTable = {
      {"world", &O::world, "world name (" + joinWorldNames() + ") or the path of a scenario .yaml"},
      {"seed", &O::seed, "seed of world generation and sensor noise", "", Range::closed(0, 1e15)},
      {"world_cache", &O::world_cache, "folder of generated worlds"},
      {"real_time_factor", &O::real_time_factor,
       "simulated seconds per wall-clock second; 0 = as fast as possible", "",
       Range::closed(0.0, 1000.0)},
      {"physics_rate", &O::physics_rate, "physics and clock rate", "Hz",
       Range::closed(10.0, 1000.0)},
      {"odometry_rate", &O::odometry_rate,
       "rate of sim/ground_truth (nav/odometry follows navigation.output_rate)", "Hz",
       Range::closed(0.1, 1000.0)},
      {"trajectory_rate", &O::trajectory_rate,
       "rows per second of ground_truth/trajectory.tum (the cameras render from it)", "Hz",
       Range::closed(1.0, 1000.0)},
      {"thruster_timeout", &O::thruster_timeout,
       "thrusters stop when no setpoint arrived for this long", "s", Range::closed(0.01, 60.0)},
      {"collision_repeat", &O::collision_repeat,
       "period of repeated collision events while a contact lasts", "s",
       Range::closed(0.01, 3600.0)},
      {"duration", &O::duration, "simulated time after which the simulation stops; 0 = unlimited",
       "s", Range::closed(0.0, 1e7)},
      {"run_dir", &O::run_dir,
       "folder for ground truth and videos; auto = auv_runs/<scenario>-<date-time>"},
      {"mission_objective",
       &O::mission_objective,
       "objective of <run>/mission.yaml: visibility (Eq. 1 + length) or path_length",
       "",
       {},
       {"visibility", "path_length"}},
      {"camera_live_rate", &O::camera_live_rate,
       "live preview frames of the scenario's cameras, JPEG on camera/<id>/compressed, per "
       "camera; 0 = none (the survey's frames are rendered afterwards by auv sim render)",
       "Hz", Range::closed(0.0, 30.0)},
      {"camera_live_scale", &O::camera_live_scale,
       "resolution of the live frames as a factor of the cameras' own", "",
       Range::aboveUpTo(0.0, 1.0)},
      {"camera_live_jpeg_quality", &O::camera_live_jpeg_quality, "JPEG quality of the live frames",
       "", Range::closed(1, 100)},
      {"camera_live_cameras", &O::camera_live_cameras,
       "cameras with live frames; empty = all of the scenario's"},
      {"faults", &O::faults,
       "injected sensor faults (fault campaign): sonar_silent@T+D, navigation_silent@T+D, "
       "dvl_lost@T+D, navigation_jump@T:DX,DY (T, D in simulated s); empty = none"},
  };
  return kTable;
}

void SimulatorComponent::configure(interfaces::Node& node) {
  node_ = &node;
  auto& p = node.parameters();
  if (options_.world_cache.empty()) options_.world_cache = defaultWorldCache();
  interfaces::declareOptions(p, "", Options::table(), options_, /*read_only=*/true);
  if (p.get<bool>("use_sim_time")) {
    throw ConfigError("simulator: use_sim_time must be false: the simulator is the clock");
  }

  const std::string scenario_path =
      ensureWorld(options_.world, options_.seed, options_.world_cache);
  scenario_ = loadScenario(scenario_path);
  MeshReport report;
  mesh_ = std::make_unique<Mesh>(loadWorldMesh(scenario_, &report));
  world_ = std::make_unique<RayCaster>(*mesh_);
  if (report.removed_degenerate > 0) {
    AUV_WARN(node.logger(), scenario_.mesh_path << ": removed " << report.removed_degenerate
                                                << " degenerate triangles");
  }

  const VehicleModel vehicle = readVehicleModel(scenario_.root.child("vehicle"));
  hull_.length = vehicle.length;
  hull_.radius = vehicle.radius;
  dynamics_ = std::make_unique<VehicleDynamics>(vehicle);
  try {
    faults_ = SensorFaults::parse(options_.faults);
  } catch (const std::invalid_argument& error) {
    throw ConfigError(std::string("simulator: parameter ") + error.what());
  }
  if (!faults_.empty()) {
    AUV_WARN(node.logger(), "injecting " << faults_.faults().size() << " sensor fault(s)");
  }
  const uint64_t seed = static_cast<uint64_t>(options_.seed);
  navigation_ = std::make_unique<NavigationSimulator>(
      NavigationOptions::fromYaml(scenario_.root.child("navigation")), seed * 2654435761u + 1);
  sonar_ = std::make_unique<ProfilingSonar>(SonarOptions::fromYaml(scenario_.root.child("sonar")),
                                            seed * 2654435761u + 2);
  const MultibeamOptions multibeam = MultibeamOptions::fromScenario(scenario_.root);
  if (multibeam.enabled) {
    multibeam_ = std::make_unique<Multibeam>(multibeam, seed * 2654435761u + 3);
  }
  const DvlBeamsOptions dvl_beams = DvlBeamsOptions::fromScenario(scenario_.root);
  if (dvl_beams.enabled) {
    dvl_beams_ = std::make_unique<DvlBeams>(dvl_beams, seed * 2654435761u + 4);
  }

  state_ = VehicleState();
  state_.position = scenario_.start_position;
  state_.yaw = scenario_.start_yaw;
  if (const auto contact = findHullContact(*world_, scenario_.seabed_depth, hull_, state_.pose())) {
    throw ConfigError(
        scenario_.file + ": vehicle.start: the hull at [" + std::to_string(state_.position.x()) +
        ", " + std::to_string(state_.position.y()) + ", " + std::to_string(state_.position.z()) +
        "] touches the world (" + std::to_string(contact->penetration) + " m deep)");
  }

  if (options_.run_dir.empty() || options_.run_dir == "auto") {
    options_.run_dir =
        (fs::path("auv_runs") / (scenario_.name + "-" + timestampForFolder())).string();
  }
  log_ = std::make_unique<GroundTruthLog>(options_.run_dir);
  writeRunScenario(scenario_, options_.run_dir);
  // The world's inspection mission, ready for `auv mission start <run>/mission.yaml`.
  MissionExportOptions mission;
  mission.objective = options_.mission_objective;
  writeMissionFile((fs::path(options_.run_dir) / "mission.yaml").string(),
                   missionYaml(scenario_, *mesh_, mission));

  clock_pub_ = node.createPublisher<msg::Clock>("clock", interfaces::clockQos());
  odometry_pub_ = node.createPublisher<msg::Odometry>("nav/odometry", interfaces::stateQos());
  ground_truth_pub_ =
      node.createPublisher<msg::Odometry>("sim/ground_truth", interfaces::stateQos());
  sonar_pub_ = node.createPublisher<msg::SonarBeam>("sonar/beam", interfaces::sensorDataQos());
  if (multibeam_) {
    scan_pub_ = node.createPublisher<msg::PointCloud>("sonar/scan", interfaces::sensorDataQos());
  }
  if (dvl_beams_) {
    dvl_beams_pub_ =
        node.createPublisher<msg::PointCloud>("dvl/beams", interfaces::sensorDataQos());
  }
  collision_pub_ =
      node.createPublisher<msg::CollisionEvent>("sim/collision", interfaces::commandQos());
  if (options_.camera_live_rate > 0) {
    LiveCameraOptions live;
    live.rate = options_.camera_live_rate;
    live.scale = options_.camera_live_scale;
    live.jpeg_quality = options_.camera_live_jpeg_quality;
    live.cameras = options_.camera_live_cameras;
    live_cameras_ = std::make_unique<LiveCameras>(node, scenario_, *world_, live);
  }
  thrusters_sub_ = node.createSubscription<msg::ThrusterSetpoints>(
      "control/thrusters", interfaces::sensorDataQos(),
      std::function<void(const msg::ThrusterSetpoints&)>([this](const msg::ThrusterSetpoints& m) {
        ThrusterCommand c{m.port(), m.starboard(), m.vertical()};
        if (!std::isfinite(c.port) || !std::isfinite(c.starboard) || !std::isfinite(c.vertical)) {
          AUV_ERROR(node_->logger(),
                    "control/thrusters: ignoring a setpoint with a non-finite "
                    "field (port, starboard or vertical)");
          return;
        }
        const double now = simulationTime();
        std::lock_guard<std::mutex> lock(thrust_mutex_);
        thrust_ = c;
        thrust_stamp_ = now;
      }));

  AUV_INFO(node.logger(), "world " << scenario_.name << " (" << report.triangles
                                   << " triangles) from " << scenario_.file << "; run folder "
                                   << options_.run_dir << "; multibeam "
                                   << (multibeam_ ? "on" : "off") << ", DVL beams "
                                   << (dvl_beams_ ? "on" : "off"));
}

void SimulatorComponent::activate() {
  running_ = true;
  thread_ = std::thread([this] { run(); });
}

void SimulatorComponent::deactivate() {
  running_ = false;
  if (thread_.joinable()) thread_.join();
  if (log_) log_->flush();
}

void SimulatorComponent::cleanup() {
  live_cameras_.reset();  // its thread renders from world_ and publishes through the node
  thrusters_sub_.reset();
  clock_pub_.reset();
  odometry_pub_.reset();
  ground_truth_pub_.reset();
  sonar_pub_.reset();
  scan_pub_.reset();
  dvl_beams_pub_.reset();
  collision_pub_.reset();
  log_.reset();
  sonar_.reset();
  multibeam_.reset();
  dvl_beams_.reset();
  navigation_.reset();
  dynamics_.reset();
  world_.reset();
  mesh_.reset();
}

VehicleState SimulatorComponent::trueState() const {
  std::lock_guard<std::mutex> lock(state_mutex_);
  return state_;
}

double SimulatorComponent::simulationTime() const {
  std::lock_guard<std::mutex> lock(state_mutex_);
  return time_;
}

void SimulatorComponent::run() {
  using Clock = std::chrono::steady_clock;
  const double dt = 1.0 / options_.physics_rate;
  const Clock::time_point wall_start = Clock::now();
  const double sim_start = simulationTime();
  double next_report = sim_start + 60.0;
  Clock::time_point next_flush = wall_start + std::chrono::seconds(1);
  bool finished = false;
  while (running_) {
    if (options_.duration > 0 && simulationTime() >= options_.duration) {
      if (!finished) {
        AUV_INFO(node_->logger(), "duration of " << options_.duration << " s reached: stopped");
        log_->flush();
        finished = true;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      continue;
    }
    try {
      step(dt);
    } catch (const std::exception& e) {
      AUV_ERROR(node_->logger(), "simulation step failed, stopping: " << e.what());
      running_ = false;
      break;
    }
    const double t = simulationTime();
    const double elapsed_sim = t - sim_start;
    if (options_.real_time_factor > 0) {
      std::this_thread::sleep_until(
          wall_start + std::chrono::duration_cast<Clock::duration>(
                           std::chrono::duration<double>(elapsed_sim / options_.real_time_factor)));
    }
    if (Clock::now() >= next_flush) {
      // Readers of the run folder (the mission report at the end of a mission) see the ground
      // truth at most a second old.
      log_->flush();
      next_flush = Clock::now() + std::chrono::seconds(1);
    }
    if (t >= next_report) {
      const double wall = std::chrono::duration<double>(Clock::now() - wall_start).count();
      AUV_INFO(node_->logger(), "t = " << t << " s, running at " << elapsed_sim / wall
                                       << "x real time, " << collisions_.load()
                                       << " collision events");
      next_report += 60.0;
    }
  }
}

double SimulatorComponent::trueAltitude(const VehicleState& state) const {
  const Eigen::Vector3f origin = state.position.cast<float>();
  const RayHit hit = world_->cast(origin, Eigen::Vector3f::UnitZ(), 200.0f);
  const double below_mesh = hit.hit() ? hit.distance : std::numeric_limits<double>::infinity();
  const double below_seabed = scenario_.seabed_depth - state.position.z();
  const double altitude = std::min(below_mesh, below_seabed);
  return altitude > 0 && std::isfinite(altitude) ? altitude : -1.0;
}

void SimulatorComponent::step(double dt) {
  ThrusterCommand command;
  VehicleState state;
  double t = 0;
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    state = state_;
    t = time_;
  }
  {
    std::lock_guard<std::mutex> lock(thrust_mutex_);
    if (t - thrust_stamp_ <= options_.thruster_timeout) command = thrust_;
  }
  dynamics_->step(state, command, dt);
  t += dt;
  checkCollision(t, state);
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    state_ = state;
    time_ = t;
  }
  publishClock(t);

  const double altitude = trueAltitude(state);
  if (altitude > 0 && last_altitude_ > 0) {
    // Roughness: how fast the seabed's distance changes, low-pass filtered over ~2 s.
    const double rate = std::abs(altitude - last_altitude_) / dt;
    roughness_ += (rate - roughness_) * std::min(1.0, dt / 2.0);
  }
  last_altitude_ = altitude;
  // A lost DVL: no bottom in range for the navigation (it dead-reckons, reports no altitude).
  const bool dvl_lost = faults_.active(SensorFaultKind::DVL_LOST, t);
  if (navigation_->update(state, t, dvl_lost ? -1.0 : altitude, roughness_)) {
    NavigationEstimate estimate = navigation_->estimate();
    estimate.position.head<2>() += faults_.navigationOffset(t);  // a jump keeps its offset
    if (!faults_.active(SensorFaultKind::NAVIGATION_SILENT, t)) {
      odometry_pub_->publish(toOdometry(estimate));
    }
    log_->navigation(t, estimate.pose());
  }
  if (t + 1e-9 >= next_odometry_) {
    next_odometry_ = t + 1.0 / options_.odometry_rate;
    ground_truth_pub_->publish(groundTruthOdometry(state, t, altitude));
  }
  if (t + 1e-9 >= next_trajectory_) {
    next_trajectory_ = t + 1.0 / options_.trajectory_rate;
    log_->trajectory(t, state.pose());
  }
  if (live_cameras_) live_cameras_->offer(t, state.pose());
  if (t + 1e-9 >= next_clearance_) {
    next_clearance_ = t + 1.0 / kClearanceRate;
    log_->clearance(
        t, hullClearance(*world_, scenario_.seabed_depth, hull_, state.pose(), kClearanceCap));
  }
  const bool sonar_silent = faults_.active(SensorFaultKind::SONAR_SILENT, t);
  while (sonar_->due(t)) {
    const auto beam = toSonarBeam(sonar_->ping(state.pose(), t, *world_));
    if (!sonar_silent) sonar_pub_->publish(beam);
  }
  pingRangeSensors(t, state, sonar_silent, dvl_lost);
}

void SimulatorComponent::pingRangeSensors(double t, const VehicleState& state, bool sonar_silent,
                                          bool dvl_lost) {
  const double seabed = scenario_.seabed_depth;
  // A silent sensor still pings on schedule (its noise stream stays as without the fault).
  if (multibeam_ && multibeam_->due(t)) {
    const auto scan = toPointCloud(multibeam_->ping(state.pose(), t, *world_, seabed));
    if (!sonar_silent) scan_pub_->publish(scan);
  }
  if (dvl_beams_ && dvl_beams_->due(t)) {
    const auto beams = toPointCloud(dvl_beams_->ping(state.pose(), t, *world_, seabed));
    if (!dvl_lost) dvl_beams_pub_->publish(beams);
  }
}

void SimulatorComponent::checkCollision(double t, VehicleState& state) {
  const auto contact = findHullContact(*world_, scenario_.seabed_depth, hull_, state.pose());
  if (!contact) {
    in_contact_ = false;
    return;
  }
  const double speed = state.velocityWorld().norm();
  const bool started = !in_contact_;
  if (started || t - last_collision_event_ >= options_.collision_repeat) {
    last_collision_event_ = t;
    ++collisions_;
    collision_pub_->publish(toCollisionEvent(*contact, state, t, speed, started));
    log_->collision(t, contact->point, contact->normal, contact->penetration, speed, started);
    if (started) {
      AUV_WARN(node_->logger(), "COLLISION at t = " << t << " s, [" << contact->point.x() << ", "
                                                    << contact->point.y() << ", "
                                                    << contact->point.z() << "] at " << speed
                                                    << " m/s");
    }
  }
  in_contact_ = true;
  // Contact response: push the hull out of the surface and remove the velocity into it.
  state.position += contact->normal * contact->penetration;
  state.position.z() = std::max(0.0, state.position.z());
  Eigen::Vector3d v = state.velocityWorld();
  const double into = v.dot(contact->normal);
  if (into < 0) v -= into * contact->normal;
  const double c = std::cos(state.yaw), s = std::sin(state.yaw);
  state.surge = c * v.x() + s * v.y();
  state.sway = -s * v.x() + c * v.y();
  state.heave = v.z();
}

void SimulatorComponent::publishClock(double t) {
  msg::Clock clock;
  clock.sim_time(toTime(t));
  clock_pub_->publish(clock);
}

}  // namespace auv::sim

AUV_REGISTER_COMPONENT(auv::sim::SimulatorComponent, "simulator",
                       "vehicle hardware stand-in: clock, dynamics, navigation, sonar, collisions")
