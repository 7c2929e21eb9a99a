// Mapping benchmark (not a test): beams/s and points/s inserted through MapBuilder (change
// tracking on, as in the component) against raw octomap::OcTree::insertPointCloud on the same
// measurements in the same run, and the ratio (issue 4 goal: >= 0.9x).
//
//   mapping_bench [--beams 200000] [--swaths 2000] [--points 256] [--resolution 0.5]
//                 [--seed 1] [--out results.md]
//
// Scene: the vehicle drives along x at 1.5 m/s down a canyon with walls at y = +-kHalfWidth and
// a floor kFloorDepth below it; a profiling sonar sweeps 360 deg at one beam per ping (returns
// beyond max range are no-return beams); a multibeam swath fans kPoints returns across the
// canyon. Raw baseline per beam: a one-point cloud (the return, or a point past max range with
// maxrange set, which clears free space only), i.e. the same cell updates.
#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>
#include <string>

#include "auv/mapping/map_builder.h"

namespace {

using Clock = std::chrono::steady_clock;
using auv::mapping::BeamGeometry;
using auv::mapping::MapBuilder;

constexpr double kHalfWidth = 8.0;    // m, canyon half width
constexpr double kFloorDepth = 6.0;   // m, floor below the vehicle
constexpr double kMaxRange = 20.0;    // m, sonar max range
constexpr double kSpeed = 1.5;        // m/s, along x
constexpr double kPingRate = 50.0;    // Hz, profiler pings
constexpr double kRangeNoise = 0.05;  // m, 1 sigma
constexpr double kSwathWidth = 2.4;   // rad, multibeam fan across the canyon

struct Args {
  std::size_t beams = 200000;
  std::size_t swaths = 2000;
  std::size_t points = 256;
  double resolution = 0.5;
  unsigned seed = 1;
  std::string out;
};

double secondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Range to the canyon walls/floor along `direction` from the vehicle, or infinity.
double rangeToCanyon(const Eigen::Vector3d& direction) {
  double range = std::numeric_limits<double>::infinity();
  if (std::abs(direction.y()) > 1e-9) range = std::min(range, kHalfWidth / std::abs(direction.y()));
  if (direction.z() > 1e-9) range = std::min(range, kFloorDepth / direction.z());
  return range;
}

struct Beam {
  Eigen::Vector3d origin;
  Eigen::Vector3d direction;
  double range;  // > kMaxRange: no return
};

}  // namespace

int main(int argc, char** argv) {
  Args args;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string key = argv[i], value = argv[i + 1];
    if (key == "--beams")
      args.beams = std::stoul(value);
    else if (key == "--swaths")
      args.swaths = std::stoul(value);
    else if (key == "--points")
      args.points = std::stoul(value);
    else if (key == "--resolution")
      args.resolution = std::stod(value);
    else if (key == "--seed")
      args.seed = static_cast<unsigned>(std::stoul(value));
    else if (key == "--out")
      args.out = value;
    else {
      std::cerr << "unknown option " << key << "\n";
      return 2;
    }
  }
  std::mt19937 random(args.seed);
  std::normal_distribution<double> noise(0.0, kRangeNoise);

  // Profiler beams: head sweeps about the vehicle's vertical axis, tilted 20 deg down.
  std::vector<Beam> beams(args.beams);
  const double tilt = 20.0 * M_PI / 180.0;
  for (std::size_t i = 0; i < beams.size(); ++i) {
    const double t = static_cast<double>(i) / kPingRate;
    const double angle = 0.9 * static_cast<double>(i) * M_PI / 180.0;  // 0.9 deg steps
    beams[i].origin = Eigen::Vector3d(kSpeed * t, 0.0, 0.0);
    beams[i].direction = Eigen::Vector3d(std::cos(angle) * std::cos(tilt),
                                         std::sin(angle) * std::cos(tilt), std::sin(tilt));
    beams[i].range = rangeToCanyon(beams[i].direction) + noise(random);
  }

  MapBuilder::Options options;
  options.resolution = args.resolution;
  MapBuilder builder(options);
  builder.enableChangeTracking(true);
  auto t0 = Clock::now();
  for (const Beam& beam : beams) {
    BeamGeometry geometry;
    geometry.direction = beam.direction;
    geometry.max_range = kMaxRange;
    if (beam.range <= kMaxRange) geometry.return_range = beam.range;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = beam.origin;
    builder.insertBeam(geometry, pose);
  }
  const double ours_beam_s = secondsSince(t0);
  builder.takeDiff();

  octomap::OcTree raw(args.resolution);
  octomap::Pointcloud one;
  t0 = Clock::now();
  for (const Beam& beam : beams) {
    one.clear();
    const double range = std::min(beam.range, kMaxRange + 1.0);  // past max range: clear only
    const Eigen::Vector3d end = beam.origin + range * beam.direction;
    one.push_back(static_cast<float>(end.x()), static_cast<float>(end.y()),
                  static_cast<float>(end.z()));
    raw.insertPointCloud(
        one,
        octomap::point3d(static_cast<float>(beam.origin.x()), static_cast<float>(beam.origin.y()),
                         static_cast<float>(beam.origin.z())),
        kMaxRange);
  }
  const double raw_beam_s = secondsSince(t0);
  std::ostringstream ours_map, raw_map;
  builder.tree().writeBinaryConst(ours_map);
  raw.writeBinaryConst(raw_map);
  const bool beam_maps_equal = ours_map.str() == raw_map.str();

  // Multibeam swaths: one cloud per swath, vertical fan across the canyon.
  std::vector<std::vector<Eigen::Vector3d>> swaths(args.swaths);
  std::vector<octomap::Pointcloud> raw_swaths(args.swaths);
  std::vector<Eigen::Vector3d> swath_origins(args.swaths);
  for (std::size_t s = 0; s < swaths.size(); ++s) {
    swath_origins[s] = Eigen::Vector3d(0.2 * static_cast<double>(s), 0.0, 0.0);
    for (std::size_t k = 0; k < args.points; ++k) {
      const double across = -kSwathWidth / 2 + kSwathWidth * static_cast<double>(k) /
                                                   static_cast<double>(args.points - 1);
      const Eigen::Vector3d direction(0.0, std::sin(across), std::cos(across));
      const double range = rangeToCanyon(direction) + noise(random);
      const Eigen::Vector3d point = swath_origins[s] + range * direction;
      swaths[s].push_back(point);
      raw_swaths[s].push_back(static_cast<float>(point.x()), static_cast<float>(point.y()),
                              static_cast<float>(point.z()));
    }
  }
  MapBuilder cloud_builder(options);
  cloud_builder.enableChangeTracking(true);
  t0 = Clock::now();
  for (std::size_t s = 0; s < swaths.size(); ++s) {
    cloud_builder.insertCloud(swaths[s], swath_origins[s], kMaxRange);
  }
  const double ours_cloud_s = secondsSince(t0);
  octomap::OcTree raw_cloud(args.resolution);
  t0 = Clock::now();
  for (std::size_t s = 0; s < swaths.size(); ++s) {
    const Eigen::Vector3d& o = swath_origins[s];
    raw_cloud.insertPointCloud(
        raw_swaths[s],
        octomap::point3d(static_cast<float>(o.x()), static_cast<float>(o.y()),
                         static_cast<float>(o.z())),
        kMaxRange);
  }
  const double raw_cloud_s = secondsSince(t0);
  std::ostringstream ours_cloud_map, raw_cloud_map;
  cloud_builder.tree().writeBinaryConst(ours_cloud_map);
  raw_cloud.writeBinaryConst(raw_cloud_map);

  const double points = static_cast<double>(args.swaths * args.points);
  const double n_beams = static_cast<double>(args.beams);
  std::ostringstream report;
  report << "# mapping_bench\n\n"
         << "resolution " << args.resolution << " m, " << args.beams << " beams, " << args.swaths
         << " swaths x " << args.points << " points, seed " << args.seed << "\n\n"
         << "| input | MapBuilder /s | raw insertPointCloud /s | ratio | same map |\n"
         << "|---|---|---|---|---|\n"
         << "| beams | " << n_beams / ours_beam_s << " | " << n_beams / raw_beam_s << " | "
         << raw_beam_s / ours_beam_s << " | " << (beam_maps_equal ? "yes" : "no") << " |\n"
         << "| points | " << points / ours_cloud_s << " | " << points / raw_cloud_s << " | "
         << raw_cloud_s / ours_cloud_s << " | "
         << (ours_cloud_map.str() == raw_cloud_map.str() ? "yes" : "no") << " |\n\n"
         << "goal: ratio >= 0.9 (issue 4)\n";
  std::cout << report.str();
  if (!args.out.empty()) {
    std::ofstream file(args.out);
    file << report.str();
    if (!file) {
      std::cerr << "cannot write " << args.out << "\n";
      return 1;
    }
  }
  return 0;
}
