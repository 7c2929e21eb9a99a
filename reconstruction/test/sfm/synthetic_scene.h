#pragma once
// Synthetic SfM problems with known answers: a rig of cameras with different intrinsics moving
// along a rocky wall (points on a wavy surface), keypoints = true projections + Gaussian noise
// in shuffled order with unmatched distractors, and verified matches for every pair that sees
// enough common points, with a fraction of wrong matches left in.

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "auv/recon/sfm/correspondences.h"

namespace auv::recon::sfm::testing {

struct SyntheticOptions {
  int cameras = 3;              ///< rig cameras (different intrinsics and orientations)
  int stations = 8;             ///< rig positions along the wall
  int points = 1500;            ///< on the wall
  double noise_px = 0.5;        ///< keypoint noise, standard deviation
  double outlier_ratio = 0.03;  ///< wrong matches added per pair, fraction of its true ones
  int distractors = 50;         ///< unmatched keypoints per image
  size_t min_pair_matches = 30;
  unsigned seed = 1;
  /// Radial distortion (k1, k2) of every camera's lens: the keypoints are projected through
  /// it, the input's cameras are the pinhole part (what a user without a calibration has).
  double k1 = 0, k2 = 0;
};

struct SyntheticScene {
  SfmInput input;
  std::map<uint32_t, scene::Image> truth;  ///< true poses, by image id
  std::vector<Eigen::Vector3d> points;
  std::map<uint32_t, std::map<uint32_t, size_t>> keypoint_point;  ///< image -> keypoint -> point
};

inline scene::Camera rigCamera(int index) {
  switch (index % 3) {
    case 0:
      return scene::Camera::pinhole(1, 1000, 750, 800, 800, 499.5, 374.5);
    case 1:
      return scene::Camera::pinhole(2, 800, 600, 620, 625, 401, 297);
    default:
      return scene::Camera::pinhole(3, 1200, 900, 1000, 1000, 610, 440);
  }
}

/// Rig mount (camera -> vehicle rotation about the vertical and the lateral axis, offset).
inline Eigen::Isometry3d rigMount(int index) {
  Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
  const double yaw[] = {0.0, -0.25, 0.25}, pitch[] = {0.0, 0.15, -0.1};
  m.linear() = (Eigen::AngleAxisd(yaw[index % 3], Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(pitch[index % 3], Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  m.translation() = Eigen::Vector3d(0.3 * (index % 3) - 0.3, 0.1 * (index % 2), 0);
  return m;  // camera frame -> vehicle frame
}

inline SyntheticScene makeSyntheticScene(const SyntheticOptions& o) {
  std::mt19937 rng(o.seed);
  std::uniform_real_distribution<double> uniform(0, 1);
  std::normal_distribution<double> noise(0, o.noise_px);
  SyntheticScene s;
  // The wall: z = 10 + wave(x, y), seen from z = 0 looking along +z.
  for (int i = 0; i < o.points; ++i) {
    const double x = -9 + 18 * uniform(rng), y = -4 + 8 * uniform(rng);
    const double z = 10 + 1.2 * std::sin(0.7 * x) * std::cos(0.9 * y) + 0.5 * uniform(rng);
    s.points.emplace_back(x, y, z);
  }
  for (int c = 0; c < o.cameras; ++c) {
    scene::Camera camera = rigCamera(c);
    camera.id = static_cast<uint32_t>(c + 1);
    s.input.cameras[camera.id] = camera;
  }
  uint32_t next_id = 1;
  for (int k = 0; k < o.stations; ++k) {
    // Vehicle pose: along x, with a little heave and yaw.
    Eigen::Isometry3d vehicle = Eigen::Isometry3d::Identity();
    const double f = o.stations > 1 ? static_cast<double>(k) / (o.stations - 1) : 0.0;
    vehicle.translation() = Eigen::Vector3d(-4 + 8 * f, 0.4 * std::sin(3 * f), 0.3 * f);
    vehicle.linear() =
        Eigen::AngleAxisd(0.1 * std::sin(5 * f), Eigen::Vector3d::UnitY()).toRotationMatrix();
    for (int c = 0; c < o.cameras; ++c) {
      scene::Camera camera = s.input.cameras.at(static_cast<uint32_t>(c + 1));
      if (o.k1 != 0 || o.k2 != 0) {
        camera.model = scene::CameraModel::OPENCV;
        camera.distortion = {o.k1, o.k2, 0, 0};
      }
      const Eigen::Isometry3d camera_to_world = vehicle * rigMount(c);
      scene::Image truth;
      truth.id = next_id++;
      truth.camera_id = camera.id;
      truth.name = "cam" + std::to_string(c) + "/" + std::to_string(k) + ".png";
      truth.setWorldToCamera(camera_to_world.inverse());
      View view;
      view.id = truth.id;
      view.camera_id = camera.id;
      view.name = truth.name;
      std::vector<std::pair<Eigen::Vector2d, long>> keypoints;  // pixel, point (-1: none)
      for (size_t p = 0; p < s.points.size(); ++p) {
        const Eigen::Vector3d x = truth.toCamera(s.points[p]);
        if (x.z() <= 0.1) continue;
        Eigen::Vector2d px = camera.project(x);
        if (!camera.inImage(px)) continue;
        px += Eigen::Vector2d(noise(rng), noise(rng));
        keypoints.push_back({px, static_cast<long>(p)});
      }
      for (int d = 0; d < o.distractors; ++d) {
        keypoints.push_back(
            {Eigen::Vector2d(uniform(rng) * camera.width, uniform(rng) * camera.height), -1});
      }
      std::shuffle(keypoints.begin(), keypoints.end(), rng);
      for (uint32_t i = 0; i < keypoints.size(); ++i) {
        view.keypoints.push_back(keypoints[i].first);
        if (keypoints[i].second >= 0) {
          s.keypoint_point[view.id][i] = static_cast<size_t>(keypoints[i].second);
        }
      }
      s.truth[truth.id] = truth;
      s.input.views.push_back(std::move(view));
    }
  }
  // Matches: every pair seeing enough common points, plus wrong ones.
  for (size_t i = 0; i < s.input.views.size(); ++i) {
    for (size_t j = i + 1; j < s.input.views.size(); ++j) {
      const View& a = s.input.views[i];
      const View& b = s.input.views[j];
      std::map<size_t, uint32_t> in_b;
      for (const auto& [k, p] : s.keypoint_point[b.id]) in_b[p] = k;
      ViewPair pair{a.id, b.id, {}, -1, std::nullopt};
      for (const auto& [k, p] : s.keypoint_point[a.id]) {
        auto it = in_b.find(p);
        if (it != in_b.end()) pair.matches.push_back({k, it->second});
      }
      if (pair.matches.size() < o.min_pair_matches) continue;
      const size_t wrong = static_cast<size_t>(o.outlier_ratio * pair.matches.size());
      for (size_t w = 0; w < wrong; ++w) {
        pair.matches.push_back(
            {static_cast<uint32_t>(uniform(rng) * a.keypoints.size()) % a.keypoints.size(),
             static_cast<uint32_t>(uniform(rng) * b.keypoints.size()) % b.keypoints.size()});
      }
      s.input.pairs.push_back(std::move(pair));
    }
  }
  return s;
}

}  // namespace auv::recon::sfm::testing
