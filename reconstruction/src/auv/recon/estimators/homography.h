#pragma once
// Homography between two views inside AC-RANSAC (ac_ransac.h): the planarity test of a
// candidate initial pair of SfM (a pair explained by a homography as well as by an essential
// matrix is planar or has no baseline; paper section 3.4.2) and the registration of [2].
//
// Model: H with x2 ~ H x1 (pixels, OpenCV convention). Minimal solver: 4 points
// (cv::getPerspectiveTransform), samples with three collinear points rejected. Residual: the
// larger of the two transfer errors |H x1 - x2| and |H^-1 x2 - x1|, px. A contrario
// normalisation: a random pixel lies within e px of a point with probability pi e^2 / A
// (d = 2), A the larger image area. Refinement: least squares + Levenberg-Marquardt on the
// inliers (cv::findHomography with method 0), kept only if the NFA does not get worse.

#include <vector>

#include <Eigen/Core>

#include "auv/recon/estimators/ac_ransac.h"
#include "auv/recon/estimators/fundamental.h"

namespace auv::recon::estimators {

class HomographyKernel {
 public:
  using Model = Eigen::Matrix3d;
  static constexpr int kMinimalSample = 4;
  static constexpr int kMaxModels = 1;

  /// Throws std::invalid_argument for point lists of different lengths or a non-positive image
  /// size.
  HomographyKernel(const std::vector<Eigen::Vector2d>& points1,
                   const std::vector<Eigen::Vector2d>& points2, ImageSize size1, ImageSize size2);

  size_t size() const { return points1_.size(); }
  void fit(const std::vector<int>& sample, std::vector<Model>* models) const;
  void residuals(const Model& homography, std::vector<double>* residuals) const;
  double logAlpha0() const { return log_alpha0_; }
  double errorDimension() const { return 2.0; }
  bool refine(const std::vector<int>& inliers, Model* homography) const;

 private:
  std::vector<Eigen::Vector2d> points1_, points2_;
  double log_alpha0_ = 0;
};

/// AC-RANSAC on the homography (kernel above).
AcRansacResult<Eigen::Matrix3d> estimateHomography(const std::vector<Eigen::Vector2d>& points1,
                                                   const std::vector<Eigen::Vector2d>& points2,
                                                   ImageSize size1, ImageSize size2,
                                                   const AcRansacOptions& options = {});

}  // namespace auv::recon::estimators
