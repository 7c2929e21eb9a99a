#include "auv/recon/estimators/two_view_util.h"

#include <opencv2/core/eigen.hpp>

namespace auv::recon::estimators::internal {

void checkPinhole(const scene::Camera& camera, const char* what) {
  if (camera.hasDistortion()) {
    throw std::invalid_argument(std::string(what) + ": camera " + std::to_string(camera.id) +
                                " has lens distortion (undistort the images first)");
  }
  if (!(camera.fx > 0) || !(camera.fy > 0)) {
    throw std::invalid_argument(std::string(what) + ": camera " + std::to_string(camera.id) +
                                " has a non-positive focal length");
  }
  checkSize(camera.width, camera.height, what);
}

void checkSize(int width, int height, const char* what) {
  if (width <= 0 || height <= 0) {
    throw std::invalid_argument(std::string(what) + ": image size " + std::to_string(width) + "x" +
                                std::to_string(height) + " (must be positive)");
  }
}

std::vector<cv::Point2d> toCv(const std::vector<Eigen::Vector2d>& points,
                              const std::vector<int>& indices) {
  std::vector<cv::Point2d> out;
  out.reserve(indices.size());
  for (int i : indices) out.emplace_back(points[i].x(), points[i].y());
  return out;
}

std::vector<cv::Point3d> toCv(const std::vector<Eigen::Vector3d>& points,
                              const std::vector<int>& indices) {
  std::vector<cv::Point3d> out;
  out.reserve(indices.size());
  for (int i : indices) out.emplace_back(points[i].x(), points[i].y(), points[i].z());
  return out;
}

void splitStacked(const cv::Mat& stacked, std::vector<Eigen::Matrix3d>* models) {
  if (stacked.empty() || stacked.cols != 3 || stacked.rows % 3 != 0) return;
  cv::Mat solutions;
  stacked.convertTo(solutions, CV_64F);
  for (int r = 0; r < solutions.rows; r += 3) {
    Eigen::Matrix3d model;
    cv::cv2eigen(solutions.rowRange(r, r + 3), model);
    if (model.allFinite() && model.norm() > 0) models->push_back(model);
  }
}

}  // namespace auv::recon::estimators::internal
