#pragma once
// The robust model fits SfM needs (paper section 3.4.2): the relative pose of the initial
// pair (essential matrix), the homography that tells a planar or rotation-only pair, and the
// absolute pose of a new view from 2D-3D correspondences (P3P). One place that calls the
// robust estimators, so the mapper does not depend on how they work.

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "auv/recon/scene/camera.h"

namespace auv::recon::sfm {

struct RobustOptions {
  double max_error_px = 4.0;   ///< px: inlier threshold (upper bound for a-contrario fits)
  double confidence = 0.9999;  ///< probability of drawing one all-inlier sample
  int max_iterations = 10000;  ///< samples at most

  /// Throws OptionError naming the field and value.
  void check() const;
};

struct RelativePose {
  bool found = false;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  ///< camera a -> camera b
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();   ///< unit length, b's frame
  std::vector<uint32_t> inliers;  ///< indices of the correspondences, in front of both cameras
  double threshold_px = 0;        ///< inlier threshold used
};

/// Essential matrix of two calibrated views (five-point solver inside a robust loop),
/// decomposed into the pose whose triangulated inliers lie in front of both cameras.
RelativePose estimateRelativePose(const scene::Camera& camera_a, const scene::Camera& camera_b,
                                  const std::vector<Eigen::Vector2d>& pixels_a,
                                  const std::vector<Eigen::Vector2d>& pixels_b,
                                  const RobustOptions& options);

/// Number of correspondences a robustly fitted homography explains within the threshold.
size_t countHomographyInliers(const std::vector<Eigen::Vector2d>& pixels_a,
                              const std::vector<Eigen::Vector2d>& pixels_b,
                              const RobustOptions& options);

struct AbsolutePose {
  bool found = false;
  Eigen::Quaterniond q_cw = Eigen::Quaterniond::Identity();  ///< world -> camera
  Eigen::Vector3d t_cw = Eigen::Vector3d::Zero();
  std::vector<uint32_t> inliers;
  double threshold_px = 0;
};

/// Pose of a calibrated camera from 2D-3D correspondences: minimal P3P samples inside a robust
/// loop, the best model re-estimated on its inliers.
AbsolutePose estimateAbsolutePose(const scene::Camera& camera,
                                  const std::vector<Eigen::Vector3d>& points,
                                  const std::vector<Eigen::Vector2d>& pixels,
                                  const RobustOptions& options);

}  // namespace auv::recon::sfm
