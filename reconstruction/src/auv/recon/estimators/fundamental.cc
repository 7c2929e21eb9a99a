#include "auv/recon/estimators/fundamental.h"

#include <cmath>
#include <limits>

#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "auv/recon/estimators/two_view_util.h"

namespace auv::recon::estimators {
namespace {

// Pixel -> [-1, 1] around the image centre (Hartley's normalisation by the image frame).
Eigen::Matrix3d frameNormalization(ImageSize size) {
  const double scale = 2.0 / std::max(size.width, size.height);
  Eigen::Matrix3d t;
  t << scale, 0, -scale * 0.5 * (size.width - 1), 0, scale, -scale * 0.5 * (size.height - 1), 0, 0,
      1;
  return t;
}

std::vector<Eigen::Vector2d> transform(const std::vector<Eigen::Vector2d>& points,
                                       const Eigen::Matrix3d& t) {
  std::vector<Eigen::Vector2d> out(points.size());
  for (size_t i = 0; i < points.size(); ++i) out[i] = (t * points[i].homogeneous()).hnormalized();
  return out;
}

double lineLogAlpha0(ImageSize size) {
  const double diagonal = std::hypot(static_cast<double>(size.width), size.height);
  return std::log10(2.0 * diagonal / (static_cast<double>(size.width) * size.height));
}

}  // namespace

double epipolarDistance(const Eigen::Matrix3d& fundamental, const Eigen::Vector2d& x1,
                        const Eigen::Vector2d& x2) {
  const Eigen::Vector3d p1 = x1.homogeneous(), p2 = x2.homogeneous();
  const Eigen::Vector3d line2 = fundamental * p1;              // in image 2
  const Eigen::Vector3d line1 = fundamental.transpose() * p2;  // in image 1
  const double norm2 = line2.head<2>().norm(), norm1 = line1.head<2>().norm();
  if (!(norm1 > 0) || !(norm2 > 0)) return std::numeric_limits<double>::infinity();
  const double algebraic = std::abs(p2.dot(line2));
  return std::max(algebraic / norm2, algebraic / norm1);
}

FundamentalKernel::FundamentalKernel(const std::vector<Eigen::Vector2d>& points1,
                                     const std::vector<Eigen::Vector2d>& points2, ImageSize size1,
                                     ImageSize size2)
    : points1_(points1), points2_(points2) {
  internal::checkCorrespondences(points1, points2, "fundamental matrix");
  internal::checkSize(size1.width, size1.height, "fundamental matrix");
  internal::checkSize(size2.width, size2.height, "fundamental matrix");
  t1_ = frameNormalization(size1);
  t2_ = frameNormalization(size2);
  scaled1_ = transform(points1_, t1_);
  scaled2_ = transform(points2_, t2_);
  log_alpha0_ = std::min(lineLogAlpha0(size1), lineLogAlpha0(size2));
}

void FundamentalKernel::fit(const std::vector<int>& sample, std::vector<Model>* models) const {
  // Exactly 7 points: OpenCV runs the 7-point solver once and returns 1 or 3 solutions stacked
  // (verified in test/estimators).
  cv::Mat stacked;
  try {
    stacked = cv::findFundamentalMat(internal::toCv(scaled1_, sample),
                                     internal::toCv(scaled2_, sample), cv::FM_7POINT);
  } catch (const cv::Exception&) {
    return;
  }
  std::vector<Eigen::Matrix3d> normalized;
  internal::splitStacked(stacked, &normalized);
  for (const Eigen::Matrix3d& f : normalized) models->push_back(t2_.transpose() * f * t1_);
}

void FundamentalKernel::residuals(const Model& fundamental, std::vector<double>* residuals) const {
  residuals->resize(points1_.size());
  for (size_t i = 0; i < points1_.size(); ++i) {
    (*residuals)[i] = epipolarDistance(fundamental, points1_[i], points2_[i]);
  }
}

bool FundamentalKernel::refine(const std::vector<int>& inliers, Model* fundamental) const {
  if (inliers.size() < 8) return false;
  cv::Mat f;
  try {
    // OpenCV's 8-point normalises the points itself (Hartley) and enforces rank 2.
    f = cv::findFundamentalMat(internal::toCv(points1_, inliers), internal::toCv(points2_, inliers),
                               cv::FM_8POINT);
  } catch (const cv::Exception&) {
    return false;
  }
  if (f.rows != 3 || f.cols != 3) return false;
  cv::cv2eigen(f, *fundamental);
  return fundamental->allFinite();
}

AcRansacResult<Eigen::Matrix3d> estimateFundamental(const std::vector<Eigen::Vector2d>& points1,
                                                    const std::vector<Eigen::Vector2d>& points2,
                                                    ImageSize size1, ImageSize size2,
                                                    const AcRansacOptions& options) {
  const FundamentalKernel kernel(points1, points2, size1, size2);
  return acRansac(kernel, options);
}

}  // namespace auv::recon::estimators
