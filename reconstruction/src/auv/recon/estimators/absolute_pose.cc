#include "auv/recon/estimators/absolute_pose.h"

#include <cmath>
#include <limits>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "auv/recon/estimators/two_view_util.h"

namespace auv::recon::estimators {
namespace {

CameraPose fromRodrigues(const cv::Mat& rvec, const cv::Mat& tvec) {
  cv::Mat r;
  cv::Rodrigues(rvec, r);
  CameraPose pose;
  cv::cv2eigen(r, pose.rotation);
  cv::Mat t;
  tvec.convertTo(t, CV_64F);
  pose.translation = Eigen::Vector3d(t.at<double>(0), t.at<double>(1), t.at<double>(2));
  return pose;
}

}  // namespace

AbsolutePoseKernel::AbsolutePoseKernel(const std::vector<Eigen::Vector2d>& points2d,
                                       const std::vector<Eigen::Vector3d>& points3d,
                                       const scene::Camera& camera)
    : points2d_(points2d), points3d_(points3d) {
  internal::checkCorrespondences(points2d, points3d, "absolute pose");
  internal::checkPinhole(camera, "absolute pose");
  fx_ = camera.fx;
  fy_ = camera.fy;
  cx_ = camera.cx;
  cy_ = camera.cy;
  log_alpha0_ = std::log10(M_PI / (static_cast<double>(camera.width) * camera.height));
}

void AbsolutePoseKernel::fit(const std::vector<int>& sample, std::vector<Model>* models) const {
  const cv::Matx33d k(fx_, 0, cx_, 0, fy_, cy_, 0, 0, 1);
  std::vector<cv::Mat> rvecs, tvecs;
  int solutions = 0;
  try {
    solutions = cv::solveP3P(internal::toCv(points3d_, sample), internal::toCv(points2d_, sample),
                             k, cv::noArray(), rvecs, tvecs, cv::SOLVEPNP_AP3P);
  } catch (const cv::Exception&) {
    return;
  }
  for (int i = 0; i < solutions; ++i) {
    const CameraPose pose = fromRodrigues(rvecs[i], tvecs[i]);
    if (pose.rotation.allFinite() && pose.translation.allFinite()) models->push_back(pose);
  }
}

void AbsolutePoseKernel::residuals(const Model& pose, std::vector<double>* residuals) const {
  residuals->resize(points2d_.size());
  for (size_t i = 0; i < points2d_.size(); ++i) {
    const Eigen::Vector3d x = pose.rotation * points3d_[i] + pose.translation;
    if (!(x.z() > 0)) {
      (*residuals)[i] = std::numeric_limits<double>::infinity();  // behind the camera
      continue;
    }
    const Eigen::Vector2d pixel(fx_ * x.x() / x.z() + cx_, fy_ * x.y() / x.z() + cy_);
    (*residuals)[i] = (pixel - points2d_[i]).norm();
  }
}

bool AbsolutePoseKernel::refine(const std::vector<int>& inliers, Model* pose) const {
  if (inliers.size() < 4) return false;
  const cv::Matx33d k(fx_, 0, cx_, 0, fy_, cy_, 0, 0, 1);
  cv::Mat r, rvec, tvec;
  cv::eigen2cv(pose->rotation, r);
  cv::Rodrigues(r, rvec);
  tvec = (cv::Mat_<double>(3, 1) << pose->translation.x(), pose->translation.y(),
          pose->translation.z());
  try {
    cv::solvePnPRefineLM(internal::toCv(points3d_, inliers), internal::toCv(points2d_, inliers), k,
                         cv::noArray(), rvec, tvec);
  } catch (const cv::Exception&) {
    return false;
  }
  const CameraPose refined = fromRodrigues(rvec, tvec);
  if (!refined.rotation.allFinite() || !refined.translation.allFinite()) return false;
  *pose = refined;
  return true;
}

AcRansacResult<CameraPose> estimateAbsolutePose(const std::vector<Eigen::Vector2d>& points2d,
                                                const std::vector<Eigen::Vector3d>& points3d,
                                                const scene::Camera& camera,
                                                const AcRansacOptions& options) {
  const AbsolutePoseKernel kernel(points2d, points3d, camera);
  return acRansac(kernel, options);
}

}  // namespace auv::recon::estimators
