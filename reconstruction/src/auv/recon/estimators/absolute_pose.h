#pragma once
// Absolute pose (resection) of a calibrated camera from 2D-3D correspondences inside AC-RANSAC
// (ac_ransac.h): how SfM registers a new view on the points already triangulated (paper
// section 3.4.2; OpenMVG resects inside AC-RANSAC as well, [3] of ac_ransac.h).
//
// Model: world -> camera pose (x_camera = R x_world + t). Minimal solver: P3P (cv::solveP3P
// with SOLVEPNP_AP3P on exactly 3 points, up to 4 solutions; the NFA over all data chooses).
// Residual: reprojection error in px; +inf for a point behind the camera. A contrario
// normalisation: pi e^2 / A (d = 2), A the image area. Refinement: Levenberg-Marquardt on the
// reprojection error of the inliers (cv::solvePnPRefineLM), kept only if the NFA does not get
// worse.

#include <vector>

#include <Eigen/Core>

#include "auv/recon/estimators/ac_ransac.h"
#include "auv/recon/scene/camera.h"

namespace auv::recon::estimators {

/// World -> camera: x_camera = rotation * x_world + translation.
struct CameraPose {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Eigen::Vector3d center() const { return -rotation.transpose() * translation; }
};

class AbsolutePoseKernel {
 public:
  using Model = CameraPose;
  static constexpr int kMinimalSample = 3;
  static constexpr int kMaxModels = 4;

  /// `points2d[i]` (px, OpenCV convention) observes `points3d[i]` (world). `camera`: pinhole
  /// (throws std::invalid_argument for distortion, lists of different lengths, a non-positive image
  /// size or focal length).
  AbsolutePoseKernel(const std::vector<Eigen::Vector2d>& points2d,
                     const std::vector<Eigen::Vector3d>& points3d, const scene::Camera& camera);

  size_t size() const { return points2d_.size(); }
  void fit(const std::vector<int>& sample, std::vector<Model>* models) const;
  void residuals(const Model& pose, std::vector<double>* residuals) const;
  double logAlpha0() const { return log_alpha0_; }
  double errorDimension() const { return 2.0; }
  bool refine(const std::vector<int>& inliers, Model* pose) const;

 private:
  std::vector<Eigen::Vector2d> points2d_;
  std::vector<Eigen::Vector3d> points3d_;
  double fx_, fy_, cx_, cy_;
  double log_alpha0_ = 0;
};

/// AC-RANSAC resection (kernel above). Use `options.max_threshold` to bound the reprojection
/// error accepted (e.g. 4 px), as OpenMVG does for resection.
AcRansacResult<CameraPose> estimateAbsolutePose(const std::vector<Eigen::Vector2d>& points2d,
                                                const std::vector<Eigen::Vector3d>& points3d,
                                                const scene::Camera& camera,
                                                const AcRansacOptions& options = {});

}  // namespace auv::recon::estimators
