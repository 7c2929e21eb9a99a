#pragma once
// Helpers shared by the two-view kernels (private to estimators/).

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "auv/recon/scene/camera.h"

namespace auv::recon::estimators::internal {

/// Throws std::invalid_argument naming `what` for lists of different lengths or a non-finite
/// coordinate.
template <class A, class B>
void checkCorrespondences(const std::vector<A>& a, const std::vector<B>& b, const char* what) {
  if (a.size() != b.size()) {
    throw std::invalid_argument(std::string(what) + ": " + std::to_string(a.size()) + " and " +
                                std::to_string(b.size()) + " points (must be equal)");
  }
  for (size_t i = 0; i < a.size(); ++i) {
    if (!a[i].allFinite() || !b[i].allFinite()) {
      throw std::invalid_argument(std::string(what) + ": point " + std::to_string(i) +
                                  " is not finite");
    }
  }
}

/// Throws std::invalid_argument naming `what` unless `camera` is a usable pinhole camera.
void checkPinhole(const scene::Camera& camera, const char* what);
/// Throws std::invalid_argument naming `what` for a non-positive size.
void checkSize(int width, int height, const char* what);

/// The points of `indices` as OpenCV points.
std::vector<cv::Point2d> toCv(const std::vector<Eigen::Vector2d>& points,
                              const std::vector<int>& indices);
std::vector<cv::Point3d> toCv(const std::vector<Eigen::Vector3d>& points,
                              const std::vector<int>& indices);

/// 3n x 3 stacked solutions of an OpenCV solver -> n matrices (non-finite ones skipped).
void splitStacked(const cv::Mat& stacked, std::vector<Eigen::Matrix3d>* models);

}  // namespace auv::recon::estimators::internal
