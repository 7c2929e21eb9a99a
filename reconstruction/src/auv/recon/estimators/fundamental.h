#pragma once
// Fundamental matrix between two uncalibrated views inside AC-RANSAC (ac_ransac.h): the
// geometric verification of a pair when a camera has no calibration (paper section 3.4.1).
//
// Model: F with x2^T F x1 = 0 for pixels x = (u, v, 1)^T (OpenCV convention). Minimal solver:
// the 7-point algorithm (cv::findFundamentalMat FM_7POINT on exactly 7 points returns 1 or 3
// solutions stacked as 3x3 blocks) on coordinates normalised by the image size (Hartley).
// Residual and a contrario normalisation as for the essential matrix (essential.h): the larger
// point-to-epipolar-line distance in px, alpha0 = 2 D / A, d = 1. Refinement: the normalised
// 8-point least-squares fit on the inliers (kept only if the NFA does not get worse).

#include <vector>

#include <Eigen/Core>

#include "auv/recon/estimators/ac_ransac.h"

namespace auv::recon::estimators {

/// Image size for the a contrario normalisation, px.
struct ImageSize {
  int width = 0;
  int height = 0;
};

class FundamentalKernel {
 public:
  using Model = Eigen::Matrix3d;
  static constexpr int kMinimalSample = 7;
  static constexpr int kMaxModels = 3;

  /// `points1[i]` <-> `points2[i]` in px of images of `size1` / `size2`. Throws
  /// std::invalid_argument for point lists of different lengths or a non-positive image size.
  FundamentalKernel(const std::vector<Eigen::Vector2d>& points1,
                    const std::vector<Eigen::Vector2d>& points2, ImageSize size1, ImageSize size2);

  size_t size() const { return points1_.size(); }
  void fit(const std::vector<int>& sample, std::vector<Model>* models) const;
  void residuals(const Model& fundamental, std::vector<double>* residuals) const;
  double logAlpha0() const { return log_alpha0_; }
  double errorDimension() const { return 1.0; }
  bool refine(const std::vector<int>& inliers, Model* fundamental) const;

 private:
  std::vector<Eigen::Vector2d> points1_, points2_;
  std::vector<Eigen::Vector2d> scaled1_, scaled2_;  ///< Hartley-normalised
  Eigen::Matrix3d t1_, t2_;                         ///< pixel -> normalised
  double log_alpha0_ = 0;
};

/// AC-RANSAC on the fundamental matrix (kernel above).
AcRansacResult<Eigen::Matrix3d> estimateFundamental(const std::vector<Eigen::Vector2d>& points1,
                                                    const std::vector<Eigen::Vector2d>& points2,
                                                    ImageSize size1, ImageSize size2,
                                                    const AcRansacOptions& options = {});

/// Distances in px of x2 to the epipolar line F x1 and of x1 to F^T x2 (the larger one).
double epipolarDistance(const Eigen::Matrix3d& fundamental, const Eigen::Vector2d& x1,
                        const Eigen::Vector2d& x2);

}  // namespace auv::recon::estimators
