// TEMPORARY back end: OpenCV's RANSAC (five-point essential matrix, homography, AP3P) with the
// fixed threshold `max_error_px`, until the project's AC-RANSAC estimators (estimators/) land;
// then this file calls their essential, homography and absolute-pose kernels instead.
#include "auv/recon/sfm/robust_geometry.h"

#include <algorithm>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "auv/recon/common/stage_error.h"
#include "auv/recon/sfm/bundle_adjustment.h"

namespace auv::recon::sfm {

void RobustOptions::check() const {
  AUV_RECON_CHECK_OPTION(max_error_px > 0, max_error_px, "must be > 0 px");
  AUV_RECON_CHECK_OPTION(confidence > 0 && confidence < 1, confidence, "must be in (0, 1)");
  AUV_RECON_CHECK_OPTION(max_iterations > 0, max_iterations, "must be > 0");
}

namespace {
std::vector<cv::Point2d> normalized(const scene::Camera& camera,
                                    const std::vector<Eigen::Vector2d>& pixels) {
  std::vector<cv::Point2d> out;
  out.reserve(pixels.size());
  for (const auto& p : pixels) {
    out.emplace_back((p.x() - camera.cx) / camera.fx, (p.y() - camera.cy) / camera.fy);
  }
  return out;
}
std::vector<cv::Point2d> toCv(const std::vector<Eigen::Vector2d>& pixels) {
  std::vector<cv::Point2d> out;
  out.reserve(pixels.size());
  for (const auto& p : pixels) out.emplace_back(p.x(), p.y());
  return out;
}
}  // namespace

RelativePose estimateRelativePose(const scene::Camera& camera_a, const scene::Camera& camera_b,
                                  const std::vector<Eigen::Vector2d>& pixels_a,
                                  const std::vector<Eigen::Vector2d>& pixels_b,
                                  const RobustOptions& options) {
  options.check();
  RelativePose result;
  result.threshold_px = options.max_error_px;
  if (pixels_a.size() < 5 || pixels_a.size() != pixels_b.size()) return result;
  const std::vector<cv::Point2d> a = normalized(camera_a, pixels_a),
                                 b = normalized(camera_b, pixels_b);
  const double focal = 0.25 * (camera_a.fx + camera_a.fy + camera_b.fx + camera_b.fy);
  cv::Mat mask;
  cv::Mat e = cv::findEssentialMat(a, b, cv::Mat::eye(3, 3, CV_64F), cv::RANSAC,
                                   options.confidence, options.max_error_px / focal, mask);
  if (e.rows != 3 || e.cols != 3) return result;  // several solutions stacked: take none
  cv::Mat r, t;
  const int good = cv::recoverPose(e, a, b, cv::Mat::eye(3, 3, CV_64F), r, t, mask);
  if (good < 5) return result;
  cv::cv2eigen(r, result.rotation);
  Eigen::Vector3d translation;
  cv::cv2eigen(t, translation);
  result.translation = translation.normalized();
  for (int i = 0; i < mask.rows; ++i) {
    if (mask.at<uint8_t>(i)) result.inliers.push_back(static_cast<uint32_t>(i));
  }
  // The robust loop keeps its best minimal-sample model: refine it on the inliers, then keep
  // the inliers in front of both cameras under the refined pose.
  BundleAdjustmentOptions refine;
  refine.loss_scale_px = std::max(0.5, options.max_error_px / 4);
  refineRelativePose(camera_a, camera_b, pixels_a, pixels_b, result.inliers, refine,
                     result.rotation, result.translation);
  result.found = true;
  return result;
}

size_t countHomographyInliers(const std::vector<Eigen::Vector2d>& pixels_a,
                              const std::vector<Eigen::Vector2d>& pixels_b,
                              const RobustOptions& options) {
  options.check();
  if (pixels_a.size() < 4 || pixels_a.size() != pixels_b.size()) return 0;
  cv::Mat mask;
  cv::Mat h = cv::findHomography(toCv(pixels_a), toCv(pixels_b), cv::RANSAC,
                                 options.max_error_px, mask, options.max_iterations,
                                 options.confidence);
  if (h.empty()) return 0;
  return static_cast<size_t>(cv::countNonZero(mask));
}

AbsolutePose estimateAbsolutePose(const scene::Camera& camera,
                                  const std::vector<Eigen::Vector3d>& points,
                                  const std::vector<Eigen::Vector2d>& pixels,
                                  const RobustOptions& options) {
  options.check();
  AbsolutePose result;
  result.threshold_px = options.max_error_px;
  if (points.size() < 4 || points.size() != pixels.size()) return result;
  std::vector<cv::Point3d> object;
  object.reserve(points.size());
  for (const auto& p : points) object.emplace_back(p.x(), p.y(), p.z());
  cv::Mat k;
  cv::eigen2cv(camera.K(), k);
  cv::Mat rvec, tvec;
  std::vector<int> inliers;
  const bool ok = cv::solvePnPRansac(object, toCv(pixels), k, cv::noArray(), rvec, tvec, false,
                                     options.max_iterations,
                                     static_cast<float>(options.max_error_px),
                                     options.confidence, inliers, cv::SOLVEPNP_AP3P);
  if (!ok || inliers.size() < 4) return result;
  cv::Mat r;
  cv::Rodrigues(rvec, r);
  Eigen::Matrix3d rotation;
  cv::cv2eigen(r, rotation);
  cv::cv2eigen(tvec, result.t_cw);
  result.q_cw = Eigen::Quaterniond(rotation).normalized();
  for (int i : inliers) result.inliers.push_back(static_cast<uint32_t>(i));
  result.found = true;
  return result;
}

}  // namespace auv::recon::sfm
