#pragma once
// Essential matrix between two calibrated views inside AC-RANSAC (ac_ransac.h): the geometric
// verification of a pair of calibrated images (paper section 3.4.1) and the two-view
// initialisation of SfM.
//
// Model: E with x2n^T E x1n = 0 for normalised coordinates xn = K^-1 (u, v, 1)^T (OpenCV pixel
// convention). Minimal solver: Nister's 5-point algorithm as OpenGV implements it (Sturm
// bracketing of the degree-10 polynomial; every real solution, up to 10). OpenCV 4.6's
// cv::findEssentialMat on 5 points gives the same solutions but took ~90 % of an AC-RANSAC
// iteration (57 % in cv::solvePoly's root iterations): iterations are 8x faster. Residual: the
// larger of the two point-to-epipolar-line distances in pixels (F = K2^-T E K1^-1). A contrario
// normalisation: a random pixel lies within e px of a line crossing an image of diagonal D and
// area A with probability <= 2 D e / A (d = 1), taken on the smaller of the two images' bounds.
// Refinement: Levenberg-Marquardt (Ceres) on R, t of E = [t]x R minimising the Sampson
// distance of the inliers, in pixels.

#include <vector>

#include <Eigen/Core>

#include "auv/recon/estimators/ac_ransac.h"
#include "auv/recon/scene/camera.h"

namespace auv::recon::estimators {

class EssentialKernel {
 public:
  using Model = Eigen::Matrix3d;
  static constexpr int kMinimalSample = 5;
  static constexpr int kMaxModels = 10;

  /// `points1[i]` <-> `points2[i]` in px (OpenCV convention) of `camera1` / `camera2`, pinhole
  /// cameras. Throws std::invalid_argument for point lists of different lengths, a camera with
  /// distortion, a non-positive image size or focal length.
  EssentialKernel(const std::vector<Eigen::Vector2d>& points1,
                  const std::vector<Eigen::Vector2d>& points2, const scene::Camera& camera1,
                  const scene::Camera& camera2);

  size_t size() const { return pixels1_.size(); }
  void fit(const std::vector<int>& sample, std::vector<Model>* models) const;
  void residuals(const Model& essential, std::vector<double>* residuals) const;
  double logAlpha0() const { return log_alpha0_; }
  double errorDimension() const { return 1.0; }
  bool refine(const std::vector<int>& inliers, Model* essential) const;

  /// F = K2^-T E K1^-1: the fundamental matrix of an essential matrix, for pixel residuals.
  Eigen::Matrix3d fundamentalOf(const Model& essential) const;

 private:
  std::vector<Eigen::Vector2d> pixels1_, pixels2_;
  std::vector<Eigen::Vector2d> normalized1_, normalized2_;
  // Unit bearing vectors of the normalised points (OpenGV's minimal solver takes these).
  std::vector<Eigen::Vector3d, Eigen::aligned_allocator<Eigen::Vector3d>> bearings1_, bearings2_;
  Eigen::Matrix3d k1_inverse_, k2_inverse_;
  double focal_ = 1;  ///< mean focal length of the two cameras, px (Sampson residual scale)
  double log_alpha0_ = 0;
};

/// AC-RANSAC on the essential matrix (kernel above).
AcRansacResult<Eigen::Matrix3d> estimateEssential(const std::vector<Eigen::Vector2d>& points1,
                                                  const std::vector<Eigen::Vector2d>& points2,
                                                  const scene::Camera& camera1,
                                                  const scene::Camera& camera2,
                                                  const AcRansacOptions& options = {});

/// Relative pose of an essential matrix: x_camera2 = R * x_camera1 + t, |t| = 1.
struct RelativePose {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  int points_in_front = 0;  ///< inliers triangulated in front of both cameras (cheirality)
};

/// Decomposes E into the four (R, t) candidates and keeps the one with the most `inliers`
/// (indices into the normalised points) in front of both cameras (cv::recoverPose's test).
RelativePose relativePoseFromEssential(const Eigen::Matrix3d& essential,
                                       const std::vector<Eigen::Vector2d>& points1,
                                       const std::vector<Eigen::Vector2d>& points2,
                                       const scene::Camera& camera1, const scene::Camera& camera2,
                                       const std::vector<int>& inliers);

}  // namespace auv::recon::estimators
