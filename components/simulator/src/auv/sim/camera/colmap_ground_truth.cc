#include "auv/sim/camera/colmap_ground_truth.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace auv::sim {
namespace fs = std::filesystem;

std::string colmapCameraLine(int camera_id, const CameraIntrinsics& k) {
  std::ostringstream line;
  line.precision(12);
  const bool full = k.distortion[4] != 0.0;
  line << camera_id << (full ? " FULL_OPENCV " : " OPENCV ") << k.width << ' ' << k.height << ' '
       << k.fx << ' ' << k.fy << ' ' << k.cx + 0.5 << ' ' << k.cy + 0.5;
  for (int i = 0; i < 4; ++i) line << ' ' << k.distortion[i];
  if (full) line << ' ' << k.distortion[4] << " 0 0 0";
  return line.str();
}

void updateColmapCameras(const std::string& path, const std::map<int, std::string>& lines,
                         const std::map<int, std::string>& names) {
  std::map<int, std::string> merged;
  if (std::ifstream in{path}) {
    std::string line;
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#') continue;
      std::istringstream fields(line);
      int id = 0;
      if (fields >> id) merged[id] = line;
    }
  }
  for (const auto& [id, line] : lines) merged[id] = line;

  const std::string temp = path + ".incomplete";
  {
    std::ofstream out(temp);
    out << "# Camera list with one line of data per camera:\n"
           "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
           "# Ground truth written by `auv sim render` (principal point in COLMAP's convention).\n"
           "# Number of cameras: "
        << merged.size() << "\n";
    for (const auto& [id, name] : names) out << "#   camera " << id << " = " << name << "\n";
    for (const auto& [id, line] : merged) out << line << "\n";
    if (!out) throw std::runtime_error(temp + ": cannot write");
  }
  fs::rename(temp, path);
}

std::string colmapImageEntry(int64_t image_id, const Eigen::Isometry3d& camera_to_world,
                             int camera_id, const std::string& name) {
  const Eigen::Isometry3d world_to_camera = camera_to_world.inverse();
  Eigen::Quaterniond q(world_to_camera.linear());
  if (q.w() < 0) q.coeffs() *= -1.0;  // same rotation; COLMAP writes qw >= 0
  const Eigen::Vector3d& t = world_to_camera.translation();
  std::ostringstream entry;
  entry.precision(12);
  entry << image_id << ' ' << q.w() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' ' << t.x()
        << ' ' << t.y() << ' ' << t.z() << ' ' << camera_id << ' ' << name << "\n\n";
  return entry.str();
}

}  // namespace auv::sim
