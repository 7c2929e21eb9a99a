#include "auv/recon/sfm/robust_geometry.h"

#include "auv/recon/common/stage_error.h"
#include "auv/recon/estimators/absolute_pose.h"
#include "auv/recon/estimators/essential.h"
#include "auv/recon/estimators/homography.h"
#include "auv/recon/sfm/triangulation.h"

namespace auv::recon::sfm {

void RobustOptions::check() const {
  AUV_RECON_CHECK_OPTION(max_error_px > 0, max_error_px, "must be > 0 px");
  AUV_RECON_CHECK_OPTION(confidence > 0 && confidence <= 1, confidence, "must be in (0, 1]");
  AUV_RECON_CHECK_OPTION(max_iterations > 0, max_iterations, "must be > 0");
}

namespace {
estimators::AcRansacOptions acRansacOptions(const RobustOptions& options) {
  estimators::AcRansacOptions ac;
  ac.max_threshold = options.max_error_px;
  ac.confidence = options.confidence;
  ac.max_iterations = options.max_iterations;
  ac.seed = options.seed;
  return ac;
}

/// The estimators work on pinhole pixels: a camera with lens distortion (self-calibrated) is
/// replaced by its pinhole part and its pixels undistorted into it.
scene::Camera pinholePart(const scene::Camera& camera) {
  scene::Camera pinhole = camera;
  pinhole.model = scene::CameraModel::PINHOLE;
  pinhole.distortion.clear();
  return pinhole;
}

std::vector<Eigen::Vector2d> undistortedPixels(const scene::Camera& camera,
                                               const std::vector<Eigen::Vector2d>& pixels) {
  std::vector<Eigen::Vector2d> out;
  out.reserve(pixels.size());
  for (const Eigen::Vector2d& pixel : pixels) {
    const Eigen::Vector2d n = camera.pixelToNormalized(pixel);
    out.emplace_back(camera.fx * n.x() + camera.cx, camera.fy * n.y() + camera.cy);
  }
  return out;
}

/// Decomposes E, keeps the pose with most inliers in front, and those inliers.
RelativePose poseFromInliers(const Eigen::Matrix3d& essential, const scene::Camera& camera_a,
                             const scene::Camera& camera_b,
                             const std::vector<Eigen::Vector2d>& pixels_a,
                             const std::vector<Eigen::Vector2d>& pixels_b,
                             const std::vector<int>& inliers, double threshold) {
  RelativePose result;
  const estimators::RelativePose pose = estimators::relativePoseFromEssential(
      essential, pixels_a, pixels_b, camera_a, camera_b, inliers);
  if (pose.points_in_front < 5) return result;
  result.rotation = pose.rotation;
  result.translation = pose.translation.normalized();
  result.threshold_px = threshold;
  // Cheirality per inlier under the chosen pose.
  Matrix34d pose_a = Matrix34d::Zero(), pose_b;
  pose_a.leftCols<3>().setIdentity();
  pose_b.leftCols<3>() = result.rotation;
  pose_b.col(3) = result.translation;
  for (int i : inliers) {
    const auto x = triangulateDlt({{pose_a, camera_a.pixelToNormalized(pixels_a[i])},
                                   {pose_b, camera_b.pixelToNormalized(pixels_b[i])}});
    if (x && depthIn(pose_a, *x) > 0 && depthIn(pose_b, *x) > 0) {
      result.inliers.push_back(static_cast<uint32_t>(i));
    }
  }
  result.found = result.inliers.size() >= 5;
  return result;
}
}  // namespace

RelativePose estimateRelativePose(const scene::Camera& camera_a, const scene::Camera& camera_b,
                                  const std::vector<Eigen::Vector2d>& pixels_a,
                                  const std::vector<Eigen::Vector2d>& pixels_b,
                                  const RobustOptions& options) {
  options.check();
  RelativePose result;
  if (pixels_a.size() < 6 || pixels_a.size() != pixels_b.size()) return result;
  const auto essential = estimators::estimateEssential(pixels_a, pixels_b, camera_a, camera_b,
                                                       acRansacOptions(options));
  if (!essential.success()) return result;
  return poseFromInliers(essential.model, camera_a, camera_b, pixels_a, pixels_b, essential.inliers,
                         essential.threshold);
}

RelativePose relativePoseFromEssential(const Eigen::Matrix3d& essential,
                                       const scene::Camera& camera_a, const scene::Camera& camera_b,
                                       const std::vector<Eigen::Vector2d>& pixels_a,
                                       const std::vector<Eigen::Vector2d>& pixels_b,
                                       const RobustOptions& options) {
  options.check();
  if (pixels_a.size() < 6 || pixels_a.size() != pixels_b.size()) return {};
  const estimators::EssentialKernel kernel(pixels_a, pixels_b, camera_a, camera_b);
  std::vector<double> residuals;
  kernel.residuals(essential, &residuals);
  std::vector<int> inliers;
  for (size_t i = 0; i < residuals.size(); ++i) {
    if (residuals[i] <= options.max_error_px) inliers.push_back(static_cast<int>(i));
  }
  return poseFromInliers(essential, camera_a, camera_b, pixels_a, pixels_b, inliers,
                         options.max_error_px);
}

size_t countHomographyInliers(const scene::Camera& camera_a, const scene::Camera& camera_b,
                              const std::vector<Eigen::Vector2d>& pixels_a,
                              const std::vector<Eigen::Vector2d>& pixels_b,
                              const RobustOptions& options) {
  options.check();
  if (pixels_a.size() < 5 || pixels_a.size() != pixels_b.size()) return 0;
  const auto homography =
      estimators::estimateHomography(pixels_a, pixels_b, {camera_a.width, camera_a.height},
                                     {camera_b.width, camera_b.height}, acRansacOptions(options));
  return homography.success() ? homography.numInliers() : 0;
}

AbsolutePose estimateAbsolutePose(const scene::Camera& camera,
                                  const std::vector<Eigen::Vector3d>& points,
                                  const std::vector<Eigen::Vector2d>& pixels,
                                  const RobustOptions& options) {
  options.check();
  AbsolutePose result;
  if (points.size() < 4 || points.size() != pixels.size()) return result;
  const auto pose =
      camera.hasDistortion()
          ? estimators::estimateAbsolutePose(undistortedPixels(camera, pixels), points,
                                             pinholePart(camera), acRansacOptions(options))
          : estimators::estimateAbsolutePose(pixels, points, camera, acRansacOptions(options));
  if (!pose.success()) return result;
  result.q_cw = Eigen::Quaterniond(pose.model.rotation).normalized();
  result.t_cw = pose.model.translation;
  result.threshold_px = pose.threshold;
  for (int i : pose.inliers) result.inliers.push_back(static_cast<uint32_t>(i));
  result.found = true;
  return result;
}

}  // namespace auv::recon::sfm
