#pragma once
// Synthetic two-view and resection problems with known answers for the estimator tests.

#include <random>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "auv/recon/scene/camera.h"

namespace auv::recon::estimators::testing {

inline scene::Camera testCamera(uint32_t id = 1) {
  return scene::Camera::pinhole(id, 1024, 768, 800.0, 810.0, 515.0, 380.0);
}

struct TwoViewScene {
  scene::Camera camera1, camera2;
  Eigen::Matrix3d rotation;                       ///< x2 = R x1 + t
  Eigen::Vector3d translation;                    ///< unit length
  std::vector<Eigen::Vector2d> points1, points2;  ///< px: inliers first, then outliers
  std::vector<Eigen::Vector2d> exact1, exact2;    ///< noise-free inlier projections
  std::vector<Eigen::Vector3d> world;             ///< inliers' 3D points (camera 1 frame)
  size_t num_inliers = 0;

  Eigen::Matrix3d essential() const {
    Eigen::Matrix3d skew;
    skew << 0, -translation.z(), translation.y(), translation.z(), 0, -translation.x(),
        -translation.y(), translation.x(), 0;
    return skew * rotation;
  }
  Eigen::Matrix3d fundamental() const {
    return camera2.K().inverse().transpose() * essential() * camera1.K().inverse();
  }
};

/// `inliers` points in a box 4-9 m in front of camera 1 (or on a plane when `planar`), seen by
/// camera 2 moved by a baseline of 1 m and rotated ~8 deg, Gaussian pixel noise `sigma`, then
/// `outliers` random pixel pairs (uniform in both images).
inline TwoViewScene makeTwoViewScene(int inliers, int outliers, double sigma, uint64_t seed,
                                     bool planar = false) {
  TwoViewScene scene;
  scene.camera1 = testCamera(1);
  scene.camera2 = testCamera(2);
  scene.rotation = (Eigen::AngleAxisd(0.10, Eigen::Vector3d::UnitY()) *
                    Eigen::AngleAxisd(-0.06, Eigen::Vector3d::UnitX()) *
                    Eigen::AngleAxisd(0.03, Eigen::Vector3d::UnitZ()))
                       .toRotationMatrix();
  scene.translation = Eigen::Vector3d(-1.0, 0.15, 0.2).normalized();
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, sigma > 0 ? sigma : 1.0);
  const double s = sigma > 0 ? 1.0 : 0.0;
  while (static_cast<int>(scene.num_inliers) < inliers) {
    Eigen::Vector3d x;
    if (planar) {
      // The plane z = 6 + 0.3 x - 0.2 y.
      x.x() = -3 + 6 * unit(random);
      x.y() = -2 + 4 * unit(random);
      x.z() = 6 + 0.3 * x.x() - 0.2 * x.y();
    } else {
      x.z() = 4 + 5 * unit(random);
      x.x() = (-0.6 + 1.2 * unit(random)) * x.z();
      x.y() = (-0.45 + 0.9 * unit(random)) * x.z();
    }
    const Eigen::Vector3d x2 = scene.rotation * x + scene.translation;
    if (x2.z() <= 0.5) continue;
    const Eigen::Vector2d p1 = scene.camera1.project(x), p2 = scene.camera2.project(x2);
    if (!scene.camera1.inImage(p1) || !scene.camera2.inImage(p2)) continue;
    scene.world.push_back(x);
    scene.exact1.push_back(p1);
    scene.exact2.push_back(p2);
    scene.points1.push_back(p1 + s * Eigen::Vector2d(noise(random), noise(random)));
    scene.points2.push_back(p2 + s * Eigen::Vector2d(noise(random), noise(random)));
    ++scene.num_inliers;
  }
  for (int i = 0; i < outliers; ++i) {
    scene.points1.emplace_back(unit(random) * 1023, unit(random) * 767);
    scene.points2.emplace_back(unit(random) * 1023, unit(random) * 767);
  }
  return scene;
}

/// Angle of a rotation matrix, degrees.
inline double rotationAngleDeg(const Eigen::Matrix3d& r) {
  return Eigen::AngleAxisd(r).angle() * 180.0 / M_PI;
}

/// Angle between two directions, degrees.
inline double angleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double c = a.normalized().dot(b.normalized());
  return std::acos(std::max(-1.0, std::min(1.0, c))) * 180.0 / M_PI;
}

}  // namespace auv::recon::estimators::testing
