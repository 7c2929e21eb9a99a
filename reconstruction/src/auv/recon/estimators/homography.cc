#include "auv/recon/estimators/homography.h"

#include <cmath>
#include <limits>

#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

#include "auv/recon/estimators/two_view_util.h"

namespace auv::recon::estimators {
namespace {

// Twice the area of the triangle abc.
double area2(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  return std::abs((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
}

// True when three of the four points are (nearly) collinear: no unique homography.
bool degenerate(const std::vector<Eigen::Vector2d>& p, const std::vector<int>& s) {
  // A triangle thinner than 1 px over its longest side is taken as a line.
  for (int skip = 0; skip < 4; ++skip) {
    std::vector<int> t;
    for (int i = 0; i < 4; ++i) {
      if (i != skip) t.push_back(s[i]);
    }
    const double longest = std::max(
        {(p[t[0]] - p[t[1]]).norm(), (p[t[1]] - p[t[2]]).norm(), (p[t[0]] - p[t[2]]).norm()});
    if (area2(p[t[0]], p[t[1]], p[t[2]]) < longest) return true;
  }
  return false;
}

double transfer(const Eigen::Matrix3d& h, const Eigen::Vector2d& from, const Eigen::Vector2d& to) {
  const Eigen::Vector3d mapped = h * from.homogeneous();
  if (!(std::abs(mapped.z()) > 1e-12)) return std::numeric_limits<double>::infinity();
  return (mapped.hnormalized() - to).norm();
}

}  // namespace

HomographyKernel::HomographyKernel(const std::vector<Eigen::Vector2d>& points1,
                                   const std::vector<Eigen::Vector2d>& points2, ImageSize size1,
                                   ImageSize size2)
    : points1_(points1), points2_(points2) {
  internal::checkCorrespondences(points1, points2, "homography");
  internal::checkSize(size1.width, size1.height, "homography");
  internal::checkSize(size2.width, size2.height, "homography");
  const double area = std::max(static_cast<double>(size1.width) * size1.height,
                               static_cast<double>(size2.width) * size2.height);
  log_alpha0_ = std::log10(M_PI / area);
}

void HomographyKernel::fit(const std::vector<int>& sample, std::vector<Model>* models) const {
  if (degenerate(points1_, sample) || degenerate(points2_, sample)) return;
  cv::Point2f from[4], to[4];
  for (int i = 0; i < 4; ++i) {
    from[i] = cv::Point2f(static_cast<float>(points1_[sample[i]].x()),
                          static_cast<float>(points1_[sample[i]].y()));
    to[i] = cv::Point2f(static_cast<float>(points2_[sample[i]].x()),
                        static_cast<float>(points2_[sample[i]].y()));
  }
  cv::Mat h;
  try {
    h = cv::getPerspectiveTransform(from, to);
  } catch (const cv::Exception&) {
    return;
  }
  Eigen::Matrix3d model;
  cv::cv2eigen(h, model);
  if (model.allFinite() && std::abs(model.determinant()) > 1e-12) models->push_back(model);
}

void HomographyKernel::residuals(const Model& homography, std::vector<double>* residuals) const {
  const Eigen::Matrix3d inverse = homography.inverse();
  residuals->resize(points1_.size());
  for (size_t i = 0; i < points1_.size(); ++i) {
    (*residuals)[i] = std::max(transfer(homography, points1_[i], points2_[i]),
                               transfer(inverse, points2_[i], points1_[i]));
  }
}

bool HomographyKernel::refine(const std::vector<int>& inliers, Model* homography) const {
  if (inliers.size() < 5) return false;
  cv::Mat h;
  try {
    // Method 0: least squares on all given points, then Levenberg-Marquardt.
    h = cv::findHomography(internal::toCv(points1_, inliers), internal::toCv(points2_, inliers), 0);
  } catch (const cv::Exception&) {
    return false;
  }
  if (h.rows != 3 || h.cols != 3) return false;
  cv::cv2eigen(h, *homography);
  return homography->allFinite() && std::abs(homography->determinant()) > 1e-12;
}

AcRansacResult<Eigen::Matrix3d> estimateHomography(const std::vector<Eigen::Vector2d>& points1,
                                                   const std::vector<Eigen::Vector2d>& points2,
                                                   ImageSize size1, ImageSize size2,
                                                   const AcRansacOptions& options) {
  const HomographyKernel kernel(points1, points2, size1, size2);
  return acRansac(kernel, options);
}

}  // namespace auv::recon::estimators
