// Poisson surface + trimming on a synthetic sea floor: time of the trimming beside the anchor,
// Open3D's screened Poisson itself, measured in the same run; false surface before and after.
//
//   mesh_bench [--points 200000] [--depth 9] [--out bench_results]
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>
#include <string>

#include "auv/recon/mesh/surface.h"

namespace o3d = open3d::geometry;
using namespace auv::recon::mesh;

namespace {

double height(double x, double y) {
  return 0.15 * std::sin(1.3 * x) * std::cos(1.1 * y) +
         0.6 * std::exp(-((x - 0.8) * (x - 0.8) + (y + 0.5) * (y + 0.5)) / 0.18);
}
Eigen::Vector3d normalAt(double x, double y) {
  const double e = 1e-5;
  const double dx = (height(x + e, y) - height(x - e, y)) / (2 * e);
  const double dy = (height(x, y + e) - height(x, y - e)) / (2 * e);
  return Eigen::Vector3d(-dx, -dy, 1).normalized();
}

double seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

int main(int argc, char** argv) {
  size_t points = 200000;
  int depth = 9;
  std::string out = "bench_results";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--points")
      points = std::stoul(argv[i + 1]);
    else if (flag == "--depth")
      depth = std::stoi(argv[i + 1]);
    else if (flag == "--out")
      out = argv[i + 1];
    else {
      std::cerr << "usage: mesh_bench [--points N] [--depth D] [--out DIR]\n";
      return 2;
    }
  }
  // A 4 m x 4 m floor with a rock, 2 mm noise, an unobserved disc of 0.5 m radius.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-2, 2);
  std::normal_distribution<double> noise(0, 0.002);
  o3d::PointCloud cloud;
  while (cloud.points_.size() < points) {
    const double x = u(rng), y = u(rng);
    if ((x + 0.7) * (x + 0.7) + (y - 0.6) * (y - 0.6) < 0.25) continue;
    cloud.points_.emplace_back(x, y, height(x, y) + noise(rng));
    cloud.normals_.push_back(normalAt(x, y));
    cloud.colors_.emplace_back(0.5, 0.5, 0.5);
  }
  SurfaceOptions options;
  options.poisson_depth = depth;
  options.threads = 1;

  auto start = std::chrono::steady_clock::now();
  auto [poisson, densities] = o3d::TriangleMesh::CreateFromPointCloudPoisson(
      cloud, depth, 0.0f, static_cast<float>(options.poisson_scale), false, 1);
  const double poisson_s = seconds(start);
  const Eigen::Vector3d extent = cloud.GetMaxBound() - cloud.GetMinBound();
  const double cell = extent.maxCoeff() * options.poisson_scale / std::pow(2.0, depth);
  o3d::TriangleMesh trimmed = *poisson;
  start = std::chrono::steady_clock::now();
  const TrimStats stats = trimSurface(trimmed, densities, cloud, cell, options);
  const double trim_s = seconds(start);

  // Area off the true floor (beyond the footprint, off its height, or inside the unobserved
  // disc) and on it.
  auto areas = [](const o3d::TriangleMesh& mesh) {
    double area = 0, on = 0;
    for (const auto& t : mesh.triangles_) {
      const Eigen::Vector3d& a = mesh.vertices_[t(0)];
      const Eigen::Vector3d& b = mesh.vertices_[t(1)];
      const Eigen::Vector3d& c = mesh.vertices_[t(2)];
      const Eigen::Vector3d m = (a + b + c) / 3;
      const bool off = std::abs(m.x()) > 2.03 || std::abs(m.y()) > 2.03 ||
                       std::abs(m.z() - height(m.x(), m.y())) > 0.03 ||
                       (m.x() + 0.7) * (m.x() + 0.7) + (m.y() - 0.6) * (m.y() - 0.6) < 0.16;
      (off ? area : on) += 0.5 * (b - a).cross(c - a).norm();
    }
    return std::make_pair(area, on);
  };
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  std::ostringstream report;
  report << "# mesh_bench: " << points << " points, Poisson depth " << depth
         << ", 1 thread (2-core machine shared with other builds: timings are noisy)\n\n"
         << "| step | seconds | triangles | false area m2 | area on the floor m2 "
            "|\n|---|---|---|---|---|\n"
         << "| Open3D screened Poisson (anchor) | " << poisson_s << " | "
         << poisson->triangles_.size() << " | " << areas(*poisson).first << " | "
         << areas(*poisson).second << " |\n"
         << "| trimming (long edges, density, components) | " << trim_s << " | "
         << trimmed.triangles_.size() << " | " << areas(trimmed).first << " | "
         << areas(trimmed).second << " |\n\n"
         << "trimming / Poisson time: " << trim_s / poisson_s << "; removed long-edge "
         << stats.removed_long_edges << ", low-density " << stats.removed_low_density
         << ", components " << stats.removed_components << " triangles; peak RSS "
         << usage.ru_maxrss / 1024 << " MB\n";
  std::cout << report.str();
  std::filesystem::create_directories(out);
  char stamp[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(stamp, sizeof(stamp), "%Y%m%d_%H%M%S", std::localtime(&now));
  const std::filesystem::path file =
      std::filesystem::path(out) / ("mesh_bench_" + std::string(stamp) + ".md");
  std::ofstream(file) << report.str();
  std::cout << "-> " << file.string() << std::endl;
  return 0;
}
