#include "auv/recon/sfm/bundle_adjustment.h"

#include <array>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include "auv/recon/common/stage_error.h"

namespace auv::recon::sfm {

std::string lossFunctionName(LossFunction loss) {
  switch (loss) {
    case LossFunction::TRIVIAL:
      return "trivial";
    case LossFunction::HUBER:
      return "huber";
    case LossFunction::CAUCHY:
      return "cauchy";
    case LossFunction::SOFT_L1:
      return "soft_l1";
  }
  return "?";
}

LossFunction lossFunctionFromName(const std::string& name) {
  for (LossFunction l :
       {LossFunction::TRIVIAL, LossFunction::HUBER, LossFunction::CAUCHY, LossFunction::SOFT_L1}) {
    if (lossFunctionName(l) == name) return l;
  }
  throw std::invalid_argument("loss '" + name + "' is not one of trivial, huber, cauchy, soft_l1");
}

void BundleAdjustmentOptions::check() const {
  AUV_RECON_CHECK_OPTION(loss_scale_px > 0, loss_scale_px, "must be > 0 px");
  AUV_RECON_CHECK_OPTION(max_iterations > 0, max_iterations, "must be > 0");
  AUV_RECON_CHECK_OPTION(function_tolerance > 0 && function_tolerance < 1, function_tolerance,
                         "must be in (0, 1)");
  AUV_RECON_CHECK_OPTION(num_threads > 0, num_threads, "must be > 0");
}

namespace {

/// Pinhole reprojection residual (px) of a world point in a camera with fixed intrinsics;
/// pose as a unit quaternion (Ceres order w, x, y, z) and a translation, world -> camera.
struct ReprojectionError {
  ReprojectionError(const Eigen::Vector2d& observed, const scene::Camera& camera)
      : u(observed.x()),
        v(observed.y()),
        fx(camera.fx),
        fy(camera.fy),
        cx(camera.cx),
        cy(camera.cy) {}

  template <class T>
  bool operator()(const T* q, const T* t, const T* x, T* residual) const {
    T p[3];
    ceres::UnitQuaternionRotatePoint(q, x, p);
    p[0] += t[0];
    p[1] += t[1];
    p[2] += t[2];
    residual[0] = T(fx) * p[0] / p[2] + T(cx) - T(u);
    residual[1] = T(fy) * p[1] / p[2] + T(cy) - T(v);
    return true;
  }

  static ceres::CostFunction* create(const Eigen::Vector2d& observed, const scene::Camera& camera) {
    return new ceres::AutoDiffCostFunction<ReprojectionError, 2, 4, 3, 3>(
        new ReprojectionError(observed, camera));
  }

  double u, v, fx, fy, cx, cy;
};

/// The same residual through the OpenCV lens model with the camera's intrinsics as one
/// parameter block {f, cx, cy, k1, k2, p1, p2} (fy = aspect * f), shared by the camera's
/// images: self-calibration of cameras that only have a prior, and the fixed intrinsics of a
/// camera whose distortion an earlier adjustment estimated.
struct LensReprojectionError {
  LensReprojectionError(const Eigen::Vector2d& observed, double aspect)
      : u(observed.x()), v(observed.y()), aspect(aspect) {}

  template <class T>
  bool operator()(const T* q, const T* t, const T* x, const T* k, T* residual) const {
    T p[3];
    ceres::UnitQuaternionRotatePoint(q, x, p);
    const T xn = (p[0] + t[0]) / (p[2] + t[2]);
    const T yn = (p[1] + t[1]) / (p[2] + t[2]);
    const T r2 = xn * xn + yn * yn;
    const T radial = T(1) + k[3] * r2 + k[4] * r2 * r2;
    const T xd = xn * radial + T(2) * k[5] * xn * yn + k[6] * (r2 + T(2) * xn * xn);
    const T yd = yn * radial + k[5] * (r2 + T(2) * yn * yn) + T(2) * k[6] * xn * yn;
    residual[0] = k[0] * xd + k[1] - T(u);
    residual[1] = T(aspect) * k[0] * yd + k[2] - T(v);
    return true;
  }

  static ceres::CostFunction* create(const Eigen::Vector2d& observed, double aspect) {
    return new ceres::AutoDiffCostFunction<LensReprojectionError, 2, 4, 3, 3, kLensParameters>(
        new LensReprojectionError(observed, aspect));
  }

  double u, v, aspect;
};

using LensBlock = std::array<double, kLensParameters>;

LensBlock toLensBlock(const scene::Camera& camera) {
  LensBlock k{camera.fx, camera.cx, camera.cy, 0, 0, 0, 0};
  for (size_t i = 0; i < 4 && i < camera.distortion.size(); ++i) k[3 + i] = camera.distortion[i];
  return k;
}

/// The adjusted block back into the camera; OPENCV once it has a distortion.
void fromLensBlock(const LensBlock& k, scene::Camera& camera) {
  const double aspect = camera.fy / camera.fx;
  camera.fx = k[0];
  camera.fy = aspect * k[0];
  camera.cx = k[1];
  camera.cy = k[2];
  if (k[3] != 0 || k[4] != 0 || k[5] != 0 || k[6] != 0) {
    camera.model = scene::CameraModel::OPENCV;
    camera.distortion = {k[3], k[4], k[5], k[6]};
  }
}

ceres::LossFunction* makeLoss(const BundleAdjustmentOptions& options) {
  const double s = options.loss_scale_px;
  switch (options.loss) {
    case LossFunction::TRIVIAL:
      return nullptr;
    case LossFunction::HUBER:
      return new ceres::HuberLoss(s);
    case LossFunction::CAUCHY:
      return new ceres::CauchyLoss(s);
    case LossFunction::SOFT_L1:
      return new ceres::SoftLOneLoss(s);
  }
  return nullptr;
}

struct PoseBlock {
  std::array<double, 4> q;  // w, x, y, z
  std::array<double, 3> t;
};

PoseBlock toBlock(const Eigen::Quaterniond& q, const Eigen::Vector3d& t) {
  const Eigen::Quaterniond n = q.normalized();
  return {{n.w(), n.x(), n.y(), n.z()}, {t.x(), t.y(), t.z()}};
}

void fromBlock(const PoseBlock& b, Eigen::Quaterniond& q, Eigen::Vector3d& t) {
  q = Eigen::Quaterniond(b.q[0], b.q[1], b.q[2], b.q[3]).normalized();
  t = Eigen::Vector3d(b.t[0], b.t[1], b.t[2]);
}

void configureSolver(ceres::Solver::Options& solver, const BundleAdjustmentOptions& options,
                     size_t variable_images) {
  solver.max_num_iterations = options.max_iterations;
  solver.function_tolerance = options.function_tolerance;
  solver.gradient_tolerance = 1e-10;
  solver.parameter_tolerance = 1e-8;
  solver.num_threads = options.num_threads;
  solver.minimizer_progress_to_stdout = false;
  solver.logging_type = ceres::SILENT;
  // Schur complement on the points: dense for a few cameras, sparse (SuiteSparse) beyond.
  solver.linear_solver_type = variable_images <= 40 ? ceres::DENSE_SCHUR : ceres::SPARSE_SCHUR;
}

}  // namespace

std::string runawayIntrinsics(const scene::Camera& refined, const scene::Camera& prior,
                              double max_focal_ratio) {
  const double ratio = refined.fx / prior.fx;
  std::ostringstream reason;
  // Radial distortion over the image: r_d = r (1 + k1 r^2 + k2 r^4) up to the farthest corner
  // must keep growing with r (else two image points share one ray) and stay within +-50 %.
  const double k1 = refined.distortion.size() > 1 ? refined.distortion[0] : 0.0;
  const double k2 = refined.distortion.size() > 1 ? refined.distortion[1] : 0.0;
  const double corner_x = std::max(refined.cx, refined.width - 1 - refined.cx) / refined.fx;
  const double corner_y = std::max(refined.cy, refined.height - 1 - refined.cy) / refined.fy;
  const double r2_max = corner_x * corner_x + corner_y * corner_y;
  bool lens_folds = false;
  for (int i = 1; i <= 20; ++i) {
    const double r2 = r2_max * i / 20.0;
    const double factor = 1 + k1 * r2 + k2 * r2 * r2;
    const double slope = 1 + 3 * k1 * r2 + 5 * k2 * r2 * r2;
    lens_folds |= !(slope > 0) || !(factor > 0.5 && factor < 1.5);
  }
  if (!std::isfinite(ratio) || ratio > max_focal_ratio || ratio < 1.0 / max_focal_ratio) {
    reason << "focal " << refined.fx << " px ran away from the prior's " << prior.fx << " px";
  } else if (lens_folds) {
    reason << "radial distortion (k1 " << k1 << ", k2 " << k2
           << ") folds or scales the image corners beyond 50 %";
  } else if (std::abs(refined.cx - 0.5 * (refined.width - 1)) > 0.25 * refined.width ||
             std::abs(refined.cy - 0.5 * (refined.height - 1)) > 0.25 * refined.height) {
    reason << "principal point (" << refined.cx << ", " << refined.cy
           << ") left the middle half of the image";
  }
  return reason.str();
}

BundleAdjustmentSummary bundleAdjust(scene::Reconstruction& rec,
                                     const BundleAdjustmentConfig& config,
                                     const BundleAdjustmentOptions& options) {
  options.check();
  const auto start = std::chrono::steady_clock::now();
  BundleAdjustmentSummary summary;

  // The points of the problem.
  std::set<uint64_t> points = config.points;
  for (uint32_t id : config.images) {
    auto it = rec.images.find(id);
    if (it == rec.images.end()) {
      throw std::invalid_argument("bundle adjustment: image " + std::to_string(id) +
                                  " is not registered");
    }
    if (!config.points.empty()) continue;
    for (int64_t p : it->second.point3d_ids) {
      if (p != scene::kNoPoint3D) points.insert(static_cast<uint64_t>(p));
    }
  }

  std::map<uint32_t, PoseBlock> poses;
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::TAKE_OWNERSHIP;
  problem_options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  problem_options.manifold_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  struct Residual {
    uint32_t image;
    uint64_t point;
    Eigen::Vector2d observed;
  };
  std::vector<Residual> residuals;
  std::set<uint32_t> fixed_pose_images;
  // The lens blocks of the cameras that this problem sees through the lens model: the
  // self-calibrated ones, and those with a distortion (held fixed unless self-calibrated).
  std::map<uint32_t, LensBlock> intrinsics;

  for (uint64_t point_id : points) {
    auto pit = rec.points.find(point_id);
    if (pit == rec.points.end()) {
      throw std::invalid_argument("bundle adjustment: point " + std::to_string(point_id) +
                                  " does not exist");
    }
    scene::Point3D& point = pit->second;
    for (const auto& obs : point.track) {
      const scene::Image& image = rec.images.at(obs.image_id);
      auto [pose, inserted] = poses.try_emplace(obs.image_id);
      if (inserted) pose->second = toBlock(image.q_cw, image.t_cw);
      const Eigen::Vector2d& observed = image.points2d[obs.point2d_idx];
      const scene::Camera& camera = rec.cameraOf(image);
      if (config.refine_focal.count(camera.id) || camera.hasDistortion()) {
        auto [k, first] = intrinsics.try_emplace(camera.id);
        if (first) k->second = toLensBlock(camera);
        problem.AddResidualBlock(LensReprojectionError::create(observed, camera.fy / camera.fx),
                                 makeLoss(options), pose->second.q.data(), pose->second.t.data(),
                                 point.xyz.data(), k->second.data());
      } else {
        problem.AddResidualBlock(ReprojectionError::create(observed, camera), makeLoss(options),
                                 pose->second.q.data(), pose->second.t.data(), point.xyz.data());
      }
      residuals.push_back({obs.image_id, point_id, observed});
    }
    if (config.constant_points.count(point_id)) problem.SetParameterBlockConstant(point.xyz.data());
  }
  if (residuals.empty()) {
    summary.usable = true;
    return summary;
  }

  // Poses: refined for `images` minus `constant_images`, fixed for the rest.
  std::vector<uint32_t> variable;
  for (auto& [id, pose] : poses) {
    if (config.images.count(id) && !config.constant_images.count(id)) {
      problem.SetManifold(pose.q.data(), new ceres::QuaternionManifold);
      variable.push_back(id);
    } else {
      problem.SetParameterBlockConstant(pose.q.data());
      problem.SetParameterBlockConstant(pose.t.data());
      fixed_pose_images.insert(id);
    }
  }
  if (config.fix_gauge && fixed_pose_images.size() < 2 && !variable.empty()) {
    size_t next = 0;
    if (fixed_pose_images.empty()) {
      const uint32_t first = variable[next++];
      problem.SetParameterBlockConstant(poses[first].q.data());
      problem.SetParameterBlockConstant(poses[first].t.data());
      fixed_pose_images.insert(first);
    }
    if (next < variable.size()) {
      // Scale about the fixed camera's centre moves t_cw of another camera along
      // R (c - c_fixed): fixing its largest component, in the camera farthest from the fixed
      // one, fixes the scale.
      const uint32_t fixed = *fixed_pose_images.begin();
      const scene::Image& a = rec.images.at(fixed);
      uint32_t other = variable[next];
      double farthest = -1;
      for (size_t i = next; i < variable.size(); ++i) {
        const double d = (rec.images.at(variable[i]).center() - a.center()).norm();
        if (d > farthest) {
          farthest = d;
          other = variable[i];
        }
      }
      const scene::Image& b = rec.images.at(other);
      const Eigen::Vector3d direction = b.q_cw * (b.center() - a.center());
      int k = 0;
      direction.cwiseAbs().maxCoeff(&k);
      problem.SetManifold(poses[other].t.data(), new ceres::SubsetManifold(3, {k}));
    }
  }

  for (auto& [id, k] : intrinsics) {
    if (!config.refine_focal.count(id)) {
      problem.SetParameterBlockConstant(k.data());
      continue;
    }
    problem.SetParameterLowerBound(k.data(), 0, 1e-3 * k[0]);  // a focal stays positive
    std::vector<int> fixed;
    if (!config.refine_principal_point) fixed.insert(fixed.end(), {1, 2});
    if (!config.refine_radial_distortion) fixed.insert(fixed.end(), {3, 4});
    if (!config.refine_tangential_distortion) fixed.insert(fixed.end(), {5, 6});
    if (!fixed.empty())
      problem.SetManifold(k.data(), new ceres::SubsetManifold(kLensParameters, fixed));
  }

  auto rms = [&]() {
    double sum = 0;
    for (const Residual& r : residuals) {
      const scene::Image& image = rec.images.at(r.image);
      const PoseBlock& pose = poses.at(r.image);
      Eigen::Quaterniond q;
      Eigen::Vector3d t;
      fromBlock(pose, q, t);
      const Eigen::Vector3d p = q * rec.points.at(r.point).xyz + t;
      const Eigen::Vector2d e = rec.cameraOf(image).project(p) - r.observed;
      sum += p.z() > 0 ? e.squaredNorm() : 1e6;
    }
    return std::sqrt(sum / residuals.size());
  };
  summary.initial_rms_px = rms();

  ceres::Solver::Options solver;
  configureSolver(solver, options, variable.size());
  ceres::Solver::Summary ceres_summary;
  ceres::Solve(solver, &problem, &ceres_summary);

  summary.usable = ceres_summary.IsSolutionUsable();
  summary.iterations = static_cast<int>(ceres_summary.iterations.size());
  summary.residuals = residuals.size();
  summary.variable_images = variable.size();
  summary.constant_pose_images = fixed_pose_images.size();
  summary.variable_points = points.size() - config.constant_points.size();
  for (const auto& [id, k] : intrinsics) {
    if (config.refine_focal.count(id)) fromLensBlock(k, rec.cameras.at(id));
  }
  summary.final_rms_px = rms();
  for (uint32_t id : variable) {
    scene::Image& image = rec.images.at(id);
    fromBlock(poses.at(id), image.q_cw, image.t_cw);
  }
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

bool refineAbsolutePose(const scene::Camera& camera, const std::vector<Eigen::Vector3d>& points,
                        const std::vector<Eigen::Vector2d>& pixels,
                        const std::vector<uint32_t>& inliers,
                        const BundleAdjustmentOptions& options, Eigen::Quaterniond& q_cw,
                        Eigen::Vector3d& t_cw) {
  options.check();
  if (inliers.size() < 3) return false;
  PoseBlock pose = toBlock(q_cw, t_cw);
  std::vector<Eigen::Vector3d> fixed(inliers.size());
  ceres::Problem problem;
  LensBlock lens = toLensBlock(camera);
  for (size_t i = 0; i < inliers.size(); ++i) {
    fixed[i] = points.at(inliers[i]);
    const Eigen::Vector2d& observed = pixels.at(inliers[i]);
    if (camera.hasDistortion()) {
      problem.AddResidualBlock(LensReprojectionError::create(observed, camera.fy / camera.fx),
                               makeLoss(options), pose.q.data(), pose.t.data(), fixed[i].data(),
                               lens.data());
    } else {
      problem.AddResidualBlock(ReprojectionError::create(observed, camera), makeLoss(options),
                               pose.q.data(), pose.t.data(), fixed[i].data());
    }
    problem.SetParameterBlockConstant(fixed[i].data());
  }
  if (camera.hasDistortion()) problem.SetParameterBlockConstant(lens.data());
  problem.SetManifold(pose.q.data(), new ceres::QuaternionManifold);
  ceres::Solver::Options solver;
  solver.max_num_iterations = options.max_iterations;
  solver.function_tolerance = options.function_tolerance;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.logging_type = ceres::SILENT;
  solver.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  if (!summary.IsSolutionUsable()) return false;
  fromBlock(pose, q_cw, t_cw);
  return true;
}

}  // namespace auv::recon::sfm
