// Simulator benchmark (not a test): ray casting rays/s per core on a world, render time per
// camera frame, and simulation speed without cameras, printed next to the targets and
// to Embree's one-ray-at-a-time path as the anchor, and written to a results file.
//
//   sim_bench [--world canyon] [--seed 1] [--rays 2000000] [--sim-seconds 300]
//             [--width 960 --height 720] [--domain 229] [--out results.md]
// Run it pinned to one core for the per-core figures: bench/run_sim_bench.sh does.
#include <sched.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <random>
#include <sstream>
#include <thread>

#include "auv/control/components/controller_component.h"
#include "auv/interfaces/executor.h"
#include "auv/sim/camera/camera_rig.h"
#include "auv/sim/camera/renderer.h"
#include "auv/sim/components/simulator_component.h"
#include "auv/sim/worldgen/world_generator.h"

namespace {

using Clock = std::chrono::steady_clock;
using namespace auv::sim;

// Restricts this thread (and the threads it starts afterwards) to `cpus` CPUs: the per-core
// figures run on one core, the render scaling on all.
void useCpus(int cpus) {
  cpu_set_t set;
  CPU_ZERO(&set);
  for (int c = 0; c < cpus; ++c) CPU_SET(c, &set);
  sched_setaffinity(0, sizeof(set), &set);
}

double secondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

struct Args {
  std::string world = "canyon";
  uint64_t seed = 1;
  size_t rays = 2000000;
  double sim_seconds = 300;
  int width = 960, height = 720;
  int domain = 229;
  std::string out;
};

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    const auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(k + " needs a value");
      return argv[++i];
    };
    if (k == "--world")
      a.world = next();
    else if (k == "--seed")
      a.seed = std::stoull(next());
    else if (k == "--rays")
      a.rays = std::stoull(next());
    else if (k == "--sim-seconds")
      a.sim_seconds = std::stod(next());
    else if (k == "--width")
      a.width = std::stoi(next());
    else if (k == "--height")
      a.height = std::stoi(next());
    else if (k == "--domain")
      a.domain = std::stoi(next());
    else if (k == "--out")
      a.out = next();
    else
      throw std::invalid_argument("unknown option " + k + " (see the file's header)");
  }
  return a;
}

// Sonar-like rays: from points along the start-to-goal routes, horizontal directions.
void sonarRays(const Scenario& scenario, size_t n, std::vector<Eigen::Vector3f>& origins,
               std::vector<Eigen::Vector3f>& dirs) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<Eigen::Vector3d> anchors{scenario.start_position};
  for (const MissionQuery& q : scenario.queries) anchors.push_back(q.goal);
  origins.resize(n);
  dirs.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const size_t k = i % (anchors.size() > 1 ? anchors.size() - 1 : 1);
    const Eigen::Vector3d& a = anchors[k];
    const Eigen::Vector3d& b = anchors.size() > 1 ? anchors[k + 1] : anchors[k];
    origins[i] = (a + (b - a) * u(rng)).cast<float>();
    const float angle = 2 * static_cast<float>(M_PI) * u(rng);
    const float tilt = (u(rng) - 0.5f) * 0.6f;  // within the vertical beam
    dirs[i] = Eigen::Vector3f(std::cos(angle), std::sin(angle), tilt).normalized();
  }
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  try {
    args = parse(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "sim_bench: " << e.what() << std::endl;
    return 2;
  }
  std::ostringstream report;
  report << std::fixed;
  const auto line = [&](const std::string& text) {
    std::cout << text << std::endl;
    report << text << "\n";
  };

  const std::string scenario_path = ensureWorld(args.world, args.seed, defaultWorldCache());
  const Scenario scenario = loadScenario(scenario_path);
  MeshReport mesh_report;
  const Mesh mesh = loadWorldMesh(scenario, &mesh_report);
  auto t0 = Clock::now();
  const RayCaster caster(mesh, scenario.surface_detail);
  const double build_s = secondsSince(t0);
  std::ostringstream head;
  head << "# Simulator benchmark: world " << scenario.name << " (seed " << args.seed << ", "
       << mesh_report.triangles << " triangles), hardware threads "
       << std::thread::hardware_concurrency() << "\n\nEmbree scene build: " << std::setprecision(3)
       << build_s << " s\n";
  line(head.str());

  // 1. Ray casting, one thread on one core.
  const int all_cpus = static_cast<int>(std::thread::hardware_concurrency());
  useCpus(1);
  std::vector<Eigen::Vector3f> origins, dirs;
  sonarRays(scenario, args.rays, origins, dirs);
  std::vector<RayHit> hits;
  caster.castMany(origins, dirs, 20.0f, hits);  // warm-up
  t0 = Clock::now();
  caster.castMany(origins, dirs, 20.0f, hits);
  const double stream_rate = args.rays / secondsSince(t0);
  size_t hit_count = 0;
  for (const RayHit& h : hits) hit_count += h.hit();
  t0 = Clock::now();
  for (size_t i = 0; i < args.rays; ++i) hits[i] = caster.cast(origins[i], dirs[i], 20.0f);
  const double single_rate = args.rays / secondsSince(t0);
  CameraRig rig = CameraRig::fromScenario(scenario);
  CameraOptions cam = rig.camera("forward");
  cam.width = args.width;
  cam.height = args.height;
  const CameraModel model(cam);
  VehicleState pose_state;
  pose_state.position = scenario.start_position;
  pose_state.yaw = scenario.start_yaw;
  const Eigen::Isometry3d camera_to_world = pose_state.pose() * cam.cameraToBody();
  std::vector<Eigen::Vector3f> cam_origins(model.rays().size(),
                                           camera_to_world.translation().cast<float>());
  std::vector<Eigen::Vector3f> cam_dirs(model.rays().size());
  const Eigen::Matrix3f R = camera_to_world.linear().cast<float>();
  for (size_t i = 0; i < cam_dirs.size(); ++i) cam_dirs[i] = R * model.rays()[i];
  std::vector<RayHit> cam_hits;
  caster.castMany(cam_origins, cam_dirs, 200.0f, cam_hits, true);  // warm-up
  t0 = Clock::now();
  caster.castMany(cam_origins, cam_dirs, 200.0f, cam_hits, /*coherent=*/true);
  const double camera_rate = cam_dirs.size() / secondsSince(t0);
  t0 = Clock::now();
  caster.castMany(cam_origins, cam_dirs, 200.0f, cam_hits, /*coherent=*/false);
  const double camera_incoherent_rate = cam_dirs.size() / secondsSince(t0);
  t0 = Clock::now();
  for (size_t i = 0; i < cam_dirs.size(); ++i) {
    cam_hits[i] = caster.cast(cam_origins[i], cam_dirs[i], 200.0f);
  }
  const double camera_single_rate = cam_dirs.size() / secondsSince(t0);
  size_t camera_hits = 0;
  for (const RayHit& h : cam_hits) camera_hits += h.hit();
  std::ostringstream rays;
  rays << std::fixed << std::setprecision(2)
       << "## Ray casting, one thread on one core (target: >= 1.00 M rays/s per core)\n\n"
       << "| rays | M rays/s | note |\n|---|---:|---|\n"
       << "| sonar-like, castMany (incoherent: one by one) | " << stream_rate / 1e6 << " | "
       << args.rays << " rays from the mission's routes, 20 m, " << (100.0 * hit_count / args.rays)
       << " % hit |\n"
       << "| sonar-like, one rtcIntersect1 per ray (Embree anchor) | " << single_rate / 1e6
       << " | same rays |\n"
       << "| camera " << args.width << "x" << args.height << ", castMany coherent | "
       << camera_rate / 1e6 << " | forward camera at the start pose, "
       << (100.0 * camera_hits / cam_dirs.size()) << " % hit |\n"
       << "| camera " << args.width << "x" << args.height << ", castMany incoherent | "
       << camera_incoherent_rate / 1e6 << " | same rays, one by one |\n"
       << "| camera, one rtcIntersect1 per ray (Embree anchor) | " << camera_single_rate / 1e6
       << " | same rays |\n";
  line(rays.str());

  // 2. Render time per frame (image formation, blur off: one exposure pose).
  std::ostringstream render;
  render << std::fixed << std::setprecision(3) << "## Render time per " << args.width << "x"
         << args.height
         << " frame (image formation included, no motion blur)\n\n| threads | s/frame "
            "|\n|---:|---:|\n";
  useCpus(all_cpus);
  for (int threads : {1, all_cpus}) {
    renderFrame(model, camera_to_world, scenario.water, caster, {}, 1, threads);  // warm-up
    t0 = Clock::now();
    const int frames = 3;
    for (int f = 0; f < frames; ++f) {
      renderFrame(model, camera_to_world, scenario.water, caster, {}, f, threads);
    }
    render << "| " << threads << " | " << secondsSince(t0) / frames << " |\n";
  }
  line(render.str());

  // 3. Simulation speed without cameras, on one core: simulator + controller composed, real
  // DDS (loopback), as fast as possible, the vehicle driving towards the first goal.
  useCpus(1);
  auv::interfaces::NodeOptions node_options;
  node_options.domain_id = args.domain;
  node_options.overrides = {"world:=" + scenario_path, "real_time_factor:=0",
                            "run_dir:=" + (std::filesystem::temp_directory_path() /
                                           ("auv_sim_bench_" + std::to_string(::getpid())))
                                              .string()};
  auv::interfaces::Node sim_node("simulator", node_options);
  auv::interfaces::NodeOptions ctrl_options;
  ctrl_options.domain_id = args.domain;
  ctrl_options.overrides = {"use_sim_time:=true"};
  auv::interfaces::Node ctrl_node("controller", ctrl_options);
  auv::interfaces::Node pilot("pilot", ctrl_options);
  SimulatorComponent sim;
  auv::control::ControllerComponent controller;
  sim.configure(sim_node);
  controller.configure(ctrl_node);
  auto command = pilot.createPublisher<auv::msg::ControllerCommand>("control/waypoint",
                                                                    auv::interfaces::commandQos());
  auv::interfaces::Executor executor;
  executor.add(sim_node);
  executor.add(ctrl_node);
  executor.add(pilot);
  controller.activate();
  auv::msg::ControllerCommand go;
  go.command_id(1);
  go.mode(auv::msg::CONTROL_MODE_WAYPOINT);
  const Eigen::Vector3d goal = scenario.queries.empty()
                                   ? scenario.start_position + Eigen::Vector3d(50, 0, 0)
                                   : scenario.queries.front().goal;
  go.position().x(goal.x());
  go.position().y(goal.y());
  go.position().z(goal.z());
  go.surge_speed(0.8);
  go.tolerance(1.0);
  executor.spinUntil([&] { return command->matchedSubscriptions() > 0; }, std::chrono::seconds(10));
  command->publish(go);
  executor.spinUntil([] { return false; }, std::chrono::milliseconds(200));
  t0 = Clock::now();
  sim.activate();
  executor.spinUntil([&] { return sim.simulationTime() >= args.sim_seconds; },
                     std::chrono::seconds(3600));
  const double wall = secondsSince(t0);
  const double simulated = sim.simulationTime();
  sim.deactivate();
  controller.deactivate();
  std::filesystem::remove_all(sim.runDir());
  std::ostringstream speed;
  speed << std::fixed << std::setprecision(1)
        << "## Simulation without cameras (target: >= 10x real time on one core)\n\n"
        << "| simulated s | wall s | x real time | collision events |\n|---:|---:|---:|---:|\n| "
        << simulated << " | " << std::setprecision(2) << wall << " | " << std::setprecision(1)
        << simulated / wall << " | " << sim.collisionCount() << " |\n\n"
        << "Physics 50 Hz, clock published every step, navigation 10 Hz, sonar "
        << "25 Hz, hull contact check every step; simulator + controller + DDS (loopback) in one "
           "process.\n";
  line(speed.str());

  if (!args.out.empty()) {
    std::ofstream out(args.out);
    out << report.str();
    std::cout << "written " << args.out << std::endl;
  }
  return 0;
}
