#include "auv/recon/estimators/essential.h"

#include <cmath>

#include <ceres/ceres.h>
#include <ceres/rotation.h>
#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opengv/relative_pose/CentralRelativeAdapter.hpp>
#include <opengv/relative_pose/methods.hpp>

#include "auv/recon/estimators/fundamental.h"
#include "auv/recon/estimators/two_view_util.h"

namespace auv::recon::estimators {
namespace {

std::vector<Eigen::Vector2d> normalize(const std::vector<Eigen::Vector2d>& pixels,
                                       const Eigen::Matrix3d& k_inverse) {
  std::vector<Eigen::Vector2d> out(pixels.size());
  for (size_t i = 0; i < pixels.size(); ++i) {
    out[i] = (k_inverse * pixels[i].homogeneous()).hnormalized();
  }
  return out;
}

// log10 of 2 D / A: the probability that a uniform random pixel lies within 1 px of a line.
double lineLogAlpha0(int width, int height) {
  const double diagonal = std::hypot(static_cast<double>(width), static_cast<double>(height));
  return std::log10(2.0 * diagonal / (static_cast<double>(width) * height));
}

// Sampson distance of one correspondence to E = [t]x R, scaled to px by the focal length.
struct SampsonCost {
  SampsonCost(const Eigen::Vector2d& x1, const Eigen::Vector2d& x2, double focal)
      : x1_(x1), x2_(x2), focal_(focal) {}

  template <class T>
  bool operator()(const T* quaternion, const T* translation, T* residual) const {
    // E = [t]x R; quaternion in Eigen order (x, y, z, w).
    const Eigen::Quaternion<T> q(quaternion[3], quaternion[0], quaternion[1], quaternion[2]);
    const Eigen::Matrix<T, 3, 1> t(translation[0], translation[1], translation[2]);
    Eigen::Matrix<T, 3, 3> skew;
    skew << T(0), -t.z(), t.y(), t.z(), T(0), -t.x(), -t.y(), t.x(), T(0);
    const Eigen::Matrix<T, 3, 3> e = skew * q.toRotationMatrix();
    const Eigen::Matrix<T, 3, 1> p1(T(x1_.x()), T(x1_.y()), T(1));
    const Eigen::Matrix<T, 3, 1> p2(T(x2_.x()), T(x2_.y()), T(1));
    const Eigen::Matrix<T, 3, 1> ex1 = e * p1;
    const Eigen::Matrix<T, 3, 1> etx2 = e.transpose() * p2;
    const T numerator = p2.dot(ex1);
    const T denominator = ex1.x() * ex1.x() + ex1.y() * ex1.y() + etx2.x() * etx2.x() +
                          etx2.y() * etx2.y() + T(1e-18);
    residual[0] = T(focal_) * numerator / ceres::sqrt(denominator);
    return true;
  }

  Eigen::Vector2d x1_, x2_;
  double focal_;
};

}  // namespace

EssentialKernel::EssentialKernel(const std::vector<Eigen::Vector2d>& points1,
                                 const std::vector<Eigen::Vector2d>& points2,
                                 const scene::Camera& camera1, const scene::Camera& camera2)
    : pixels1_(points1), pixels2_(points2) {
  internal::checkCorrespondences(points1, points2, "essential matrix");
  internal::checkPinhole(camera1, "essential matrix");
  internal::checkPinhole(camera2, "essential matrix");
  k1_inverse_ = camera1.K().inverse();
  k2_inverse_ = camera2.K().inverse();
  normalized1_ = normalize(pixels1_, k1_inverse_);
  normalized2_ = normalize(pixels2_, k2_inverse_);
  bearings1_.reserve(size());
  bearings2_.reserve(size());
  for (size_t i = 0; i < size(); ++i) {
    bearings1_.push_back(normalized1_[i].homogeneous().normalized());
    bearings2_.push_back(normalized2_[i].homogeneous().normalized());
  }
  focal_ = 0.25 * (camera1.fx + camera1.fy + camera2.fx + camera2.fy);
  // max(d1, d2) <= e implies each d <= e: the tighter of the two images' bounds holds.
  log_alpha0_ = std::min(lineLogAlpha0(camera1.width, camera1.height),
                         lineLogAlpha0(camera2.width, camera2.height));
}

void EssentialKernel::fit(const std::vector<int>& sample, std::vector<Model>* models) const {
  // OpenGV's E = [t]x R maps viewpoint 2 to 1 (f1^T E f2 = 0); this kernel's maps 1 to 2.
  // The adapter only refers to the bearing vectors, and lives on the stack: OpenGV's deleting
  // destructor (built without C++17's aligned new) frees with Eigen's free what our C++17
  // `new` would have allocated with operator new (ASan: alloc-dealloc-mismatch).
  const opengv::relative_pose::CentralRelativeAdapter adapter(bearings1_, bearings2_);
  for (const Eigen::Matrix3d& e : opengv::relative_pose::fivept_nister(adapter, sample)) {
    if (e.allFinite()) models->push_back(e.transpose());
  }
}

Eigen::Matrix3d EssentialKernel::fundamentalOf(const Model& essential) const {
  return k2_inverse_.transpose() * essential * k1_inverse_;
}

void EssentialKernel::residuals(const Model& essential, std::vector<double>* residuals) const {
  const Eigen::Matrix3d f = fundamentalOf(essential);
  residuals->resize(pixels1_.size());
  for (size_t i = 0; i < pixels1_.size(); ++i) {
    (*residuals)[i] = epipolarDistance(f, pixels1_[i], pixels2_[i]);
  }
}

bool EssentialKernel::refine(const std::vector<int>& inliers, Model* essential) const {
  if (inliers.size() < 6) return false;
  // Start from the decomposition that puts the inliers in front of both cameras.
  cv::Mat e_cv, r_cv, t_cv;
  cv::eigen2cv(*essential, e_cv);
  const std::vector<cv::Point2d> x1 = internal::toCv(normalized1_, inliers);
  const std::vector<cv::Point2d> x2 = internal::toCv(normalized2_, inliers);
  try {
    if (cv::recoverPose(e_cv, x1, x2, cv::Mat::eye(3, 3, CV_64F), r_cv, t_cv) <= 0) return false;
  } catch (const cv::Exception&) {
    return false;
  }
  Eigen::Matrix3d rotation;
  Eigen::Vector3d translation;
  cv::cv2eigen(r_cv, rotation);
  cv::cv2eigen(t_cv, translation);
  Eigen::Quaterniond q(rotation);
  double quaternion[4] = {q.x(), q.y(), q.z(), q.w()};
  double t[3] = {translation.x(), translation.y(), translation.z()};

  ceres::Problem problem;
  for (int i : inliers) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<SampsonCost, 1, 4, 3>(
                                 new SampsonCost(normalized1_[i], normalized2_[i], focal_)),
                             nullptr, quaternion, t);
  }
  problem.SetManifold(quaternion, new ceres::EigenQuaternionManifold);
  problem.SetManifold(t, new ceres::SphereManifold<3>);
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = 50;
  options.num_threads = 1;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  if (!summary.IsSolutionUsable()) return false;

  const Eigen::Quaterniond refined(quaternion[3], quaternion[0], quaternion[1], quaternion[2]);
  const Eigen::Vector3d refined_t(t[0], t[1], t[2]);
  Eigen::Matrix3d skew;
  skew << 0, -refined_t.z(), refined_t.y(), refined_t.z(), 0, -refined_t.x(), -refined_t.y(),
      refined_t.x(), 0;
  *essential = skew * refined.normalized().toRotationMatrix();
  return essential->allFinite();
}

AcRansacResult<Eigen::Matrix3d> estimateEssential(const std::vector<Eigen::Vector2d>& points1,
                                                  const std::vector<Eigen::Vector2d>& points2,
                                                  const scene::Camera& camera1,
                                                  const scene::Camera& camera2,
                                                  const AcRansacOptions& options) {
  const EssentialKernel kernel(points1, points2, camera1, camera2);
  return acRansac(kernel, options);
}

RelativePose relativePoseFromEssential(const Eigen::Matrix3d& essential,
                                       const std::vector<Eigen::Vector2d>& points1,
                                       const std::vector<Eigen::Vector2d>& points2,
                                       const scene::Camera& camera1, const scene::Camera& camera2,
                                       const std::vector<int>& inliers) {
  internal::checkCorrespondences(points1, points2, "relative pose");
  internal::checkPinhole(camera1, "relative pose");
  internal::checkPinhole(camera2, "relative pose");
  RelativePose pose;
  if (inliers.size() < 5) return pose;
  const std::vector<Eigen::Vector2d> n1 = normalize(points1, camera1.K().inverse());
  const std::vector<Eigen::Vector2d> n2 = normalize(points2, camera2.K().inverse());
  cv::Mat e_cv, r_cv, t_cv;
  cv::eigen2cv(essential, e_cv);
  try {
    pose.points_in_front =
        cv::recoverPose(e_cv, internal::toCv(n1, inliers), internal::toCv(n2, inliers),
                        cv::Mat::eye(3, 3, CV_64F), r_cv, t_cv);
  } catch (const cv::Exception&) {
    return pose;
  }
  cv::cv2eigen(r_cv, pose.rotation);
  cv::cv2eigen(t_cv, pose.translation);
  return pose;
}

}  // namespace auv::recon::estimators
