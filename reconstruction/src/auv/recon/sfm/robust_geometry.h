#pragma once
// The robust model fits SfM needs (paper section 3.4.2): the relative pose of the initial
// pair (essential matrix), the homography that tells a planar or rotation-only pair, and the
// absolute pose of a new view from 2D-3D correspondences (P3P). All through AC-RANSAC
// (estimators/, Moisan-Moulon-Monasse): the inlier threshold is chosen per model, bounded by
// `max_error_px`. One place that calls the estimators, so the mapper does not depend on them.

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "auv/recon/scene/camera.h"

namespace auv::recon::sfm {

struct RobustOptions {
  double max_error_px = 4.0;   ///< px: upper bound of AC-RANSAC's adaptive threshold
  double confidence = 0.9999;  ///< early stop: probability of one all-inlier sample drawn
  int max_iterations = 1000;   ///< minimal samples at most (10 % of them focused on the best
                               ///< model's inliers, the rest stopped early by `confidence`)
  uint64_t seed = 42;          ///< random samples (runs are repeatable)

  /// Throws OptionError naming the field and value.
  void check() const;
};

struct RelativePose {
  bool found = false;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  ///< camera a -> camera b
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();   ///< unit length, b's frame
  std::vector<uint32_t> inliers;  ///< indices of the correspondences, in front of both cameras
  double threshold_px = 0;        ///< AC-RANSAC's adaptive threshold
};

/// Essential matrix of two calibrated views (five-point solver in AC-RANSAC, refined on the
/// inliers), decomposed into the pose that puts most inliers in front of both cameras; the
/// inliers behind either camera are left out.
RelativePose estimateRelativePose(const scene::Camera& camera_a, const scene::Camera& camera_b,
                                  const std::vector<Eigen::Vector2d>& pixels_a,
                                  const std::vector<Eigen::Vector2d>& pixels_b,
                                  const RobustOptions& options);

/// The relative pose of an essential matrix already estimated (the pair's verification):
/// inliers = correspondences within `max_error_px` of their epipolar lines and in front of
/// both cameras under the decomposed pose.
RelativePose relativePoseFromEssential(const Eigen::Matrix3d& essential,
                                       const scene::Camera& camera_a, const scene::Camera& camera_b,
                                       const std::vector<Eigen::Vector2d>& pixels_a,
                                       const std::vector<Eigen::Vector2d>& pixels_b,
                                       const RobustOptions& options);

/// Number of correspondences an AC-RANSAC homography explains (0 when none is meaningful).
size_t countHomographyInliers(const scene::Camera& camera_a, const scene::Camera& camera_b,
                              const std::vector<Eigen::Vector2d>& pixels_a,
                              const std::vector<Eigen::Vector2d>& pixels_b,
                              const RobustOptions& options);

struct AbsolutePose {
  bool found = false;
  Eigen::Quaterniond q_cw = Eigen::Quaterniond::Identity();  ///< world -> camera
  Eigen::Vector3d t_cw = Eigen::Vector3d::Zero();
  std::vector<uint32_t> inliers;
  double threshold_px = 0;
};

/// Pose of a calibrated camera from 2D-3D correspondences: minimal P3P samples in AC-RANSAC,
/// the best model refined on its inliers. A camera with lens distortion is handled through its
/// undistorted pixels (the threshold then applies to those).
AbsolutePose estimateAbsolutePose(const scene::Camera& camera,
                                  const std::vector<Eigen::Vector3d>& points,
                                  const std::vector<Eigen::Vector2d>& pixels,
                                  const RobustOptions& options);

}  // namespace auv::recon::sfm
