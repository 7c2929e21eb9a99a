#pragma once
// Small synthetic worlds with known answers for the evaluate tests: a flat seabed with a wall,
// down-looking cameras along a line, a simulator-like run folder (ground_truth/cameras.txt,
// images_<camera>.txt, scenario.yaml + mesh) and a survey whose sparse model is the truth
// moved by a known similarity.

#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <open3d/geometry/TriangleMesh.h>
#include <Eigen/Geometry>

#include "auv/recon/evaluate/alignment.h"
#include "auv/recon/scene/colmap_text.h"
#include "auv/recon/scene/ply.h"

namespace auv::recon::evaluate::testing {

namespace fs = std::filesystem;

/// A fresh folder under the system's temporary directory (not the working directory: a test
/// run from the source tree must not leave folders in it).
inline fs::path freshFolder(const std::string& name) {
  const fs::path folder = fs::temp_directory_path() / ("auv_evaluate_test_" + name);
  fs::remove_all(folder);
  fs::create_directories(folder);
  return folder;
}

/// A horizontal square plane at depth `depth` (NED z), `size` m wide, centred at (cx, cy),
/// split into n x n cells of two triangles.
inline open3d::geometry::TriangleMesh planeMesh(double depth, double size, int n, double cx = 0,
                                                double cy = 0) {
  open3d::geometry::TriangleMesh mesh;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) {
      mesh.vertices_.emplace_back(cx - size / 2 + size * i / n, cy - size / 2 + size * j / n,
                                  depth);
    }
  }
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const int a = i * (n + 1) + j, b = a + 1, c = a + n + 1, d = c + 1;
      mesh.triangles_.emplace_back(a, c, b);
      mesh.triangles_.emplace_back(b, c, d);
    }
  }
  return mesh;
}

/// A down-looking camera (optical axis +z NED, image x along world +y) at `center`.
inline scene::Image downCamera(uint32_t id, uint32_t camera_id, const Eigen::Vector3d& center,
                               const std::string& name) {
  scene::Image image;
  image.id = id;
  image.camera_id = camera_id;
  image.name = name;
  Eigen::Matrix3d R_wc;  // columns: camera axes in the world
  R_wc.col(0) = Eigen::Vector3d::UnitY();
  R_wc.col(1) = -Eigen::Vector3d::UnitX();
  R_wc.col(2) = Eigen::Vector3d::UnitZ();
  image.q_cw = Eigen::Quaterniond(R_wc.transpose());
  image.t_cw = -(R_wc.transpose() * center);
  return image;
}

/// The similarity used to make "reconstructions" out of the truth: truth = s R x + t.
inline Similarity knownSimilarity() {
  Similarity s;
  s.scale = 2.5;
  s.rotation = (Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()) *
                Eigen::AngleAxisd(-0.3, Eigen::Vector3d::UnitZ()))
                   .toRotationMatrix();
  s.translation = Eigen::Vector3d(4.0, -7.0, 1.5);
  return s;
}

/// An image posed in the truth frame moved into the reconstruction frame of `truth_from_rec`.
inline scene::Image toReconstruction(const scene::Image& truth, const Similarity& truth_from_rec) {
  // x_camera ~ R_t (s R x + t) + t_t: rotation R_t R, centre rec_from_truth(true centre).
  scene::Image image = truth;
  const Eigen::Matrix3d R = truth.rotation() * truth_from_rec.rotation;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = R;
  pose.translation() = -R * truth_from_rec.inverse().apply(truth.center());
  image.setWorldToCamera(pose);
  return image;
}

/// Writes a simulator-like run folder:
///   scenario.yaml (world.mesh = world.ply, z-up mesh = NED (x, -y, -z)), water.visibility,
///   ground_truth/cameras.txt (camera 1 "left"), ground_truth/images_left.txt (NAME
///   left_0001.mp4#<frame>), trajectory.tum and navigation.tum.
inline void writeRun(const fs::path& run, const open3d::geometry::TriangleMesh& world_ned,
                     const scene::Camera& camera, const std::vector<scene::Image>& frames,
                     double visibility = 6.0) {
  fs::create_directories(run / "ground_truth");
  scene::PlyData ply;
  for (const auto& v : world_ned.vertices_) ply.positions.emplace_back(v.x(), -v.y(), -v.z());
  for (const auto& t : world_ned.triangles_) {
    ply.triangles.push_back(
        {static_cast<uint32_t>(t(0)), static_cast<uint32_t>(t(2)), static_cast<uint32_t>(t(1))});
  }
  scene::writePly(run / "world.ply", ply);
  std::ofstream(run / "scenario.yaml")
      << "name: synthetic\nworld:\n  mesh: world.ply\n"
      << "  up_axis: z\nwater:\n  visibility: " << visibility << "\n";
  scene::Reconstruction truth;
  truth.cameras[camera.id] = camera;
  for (const auto& image : frames) truth.images[image.id] = image;
  const fs::path temp = run / "ground_truth" / "tmp";
  scene::writeColmapText(truth, temp);
  fs::rename(temp / "cameras.txt", run / "ground_truth" / "cameras.txt");
  fs::rename(temp / "images.txt", run / "ground_truth" / "images_left.txt");
  fs::remove_all(temp);
  std::ofstream tum(run / "ground_truth" / "trajectory.tum");
  std::ofstream nav(run / "ground_truth" / "navigation.tum");
  tum << "# true body pose\n";
  double t = 0;
  for (const auto& image : frames) {
    const Eigen::Vector3d c = image.center();
    tum << t << " " << c.x() << " " << c.y() << " " << c.z() << " 0 0 0 1\n";
    nav << t << " " << c.x() + 0.1 * t << " " << c.y() << " " << c.z() << " 0 0 0 1\n";
    t += 1.0;
  }
}

}  // namespace auv::recon::evaluate::testing
