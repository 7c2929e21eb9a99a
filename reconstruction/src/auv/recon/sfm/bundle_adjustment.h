#pragma once
// Bundle adjustment with Ceres (paper section 3.4.2): camera poses and 3D points refined to
// minimise the robustified reprojection error in pixels. The intrinsics stay fixed when they
// come from the pattern calibration (paper 3.3); cameras that only have a prior (EXIF, stated,
// default: import/README.md) may have their focal length, radial (and optionally tangential)
// distortion and optionally their principal point refined too (self-calibration through the
// OpenCV lens model, shared by every image of the camera).

#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "auv/recon/scene/reconstruction.h"

namespace auv::recon::sfm {

/// Robust loss on the reprojection error r (px), with scale s = loss_scale_px:
/// TRIVIAL r^2; HUBER quadratic up to s, then linear; CAUCHY s^2 log(1 + r^2/s^2) (what COLMAP
/// uses: a wrong match beyond a few s barely pulls); SOFT_L1 2 s^2 (sqrt(1 + r^2/s^2) - 1).
enum class LossFunction { TRIVIAL, HUBER, CAUCHY, SOFT_L1 };
std::string lossFunctionName(LossFunction loss);
/// Throws std::invalid_argument for an unknown name.
LossFunction lossFunctionFromName(const std::string& name);

struct BundleAdjustmentOptions {
  LossFunction loss = LossFunction::CAUCHY;
  double loss_scale_px = 1.0;        ///< px: residual where the robust loss starts to bend
  int max_iterations = 100;          ///< Levenberg-Marquardt iterations
  double function_tolerance = 1e-6;  ///< relative cost change that ends the solve
  int num_threads = 2;

  /// Throws OptionError naming the field and value.
  void check() const;
};

/// Which parameters a bundle adjustment touches. Every observation of `points` (all points
/// seen by `images` when `points` is empty) enters the problem; images that see them but are
/// not in `images` keep their poses fixed.
struct BundleAdjustmentConfig {
  std::set<uint32_t> images;           ///< poses refined (unless also in constant_images)
  std::set<uint32_t> constant_images;  ///< of `images`: poses fixed (gauge)
  std::set<uint64_t> points;           ///< empty: every point seen by `images`
  std::set<uint64_t> constant_points;  ///< positions fixed
  /// The 7-dof gauge (similarity) of a problem without two fixed poses: when fewer than two
  /// images have a fixed pose, the first refined image is fixed and one translation component
  /// of the next keeps the scale. Local BA has fixed neighbours and does not need it.
  bool fix_gauge = true;
  /// Cameras whose focal length is refined (fy/fx kept), shared by their images.
  std::set<uint32_t> refine_focal;
  bool refine_principal_point = false;        ///< and, for those, (cx, cy)
  bool refine_radial_distortion = false;      ///< and k1, k2 (the camera becomes OPENCV)
  bool refine_tangential_distortion = false;  ///< and p1, p2
};

/// Parameters of the lens block of a self-calibrated camera: f, cx, cy, k1, k2, p1, p2.
constexpr int kLensParameters = 7;

struct BundleAdjustmentSummary {
  bool usable = false;  ///< Ceres reached a usable solution
  int iterations = 0;
  size_t residuals = 0, variable_images = 0, constant_pose_images = 0, variable_points = 0;
  double initial_rms_px = 0, final_rms_px = 0;  ///< plain (not robustified) reprojection RMS
  double seconds = 0;
};

/// Why a self-calibrated camera has run away from its prior (a focal beyond `max_focal_ratio`
/// of the prior's either way, a radial distortion that folds the image or scales its corners
/// beyond 50 %, or a principal point outside the middle half of the image), or empty when it
/// has not.
std::string runawayIntrinsics(const scene::Camera& refined, const scene::Camera& prior,
                              double max_focal_ratio);

/// Adjusts `reconstruction` in place. Throws std::invalid_argument for ids not in it.
BundleAdjustmentSummary bundleAdjust(scene::Reconstruction& reconstruction,
                                     const BundleAdjustmentConfig& config,
                                     const BundleAdjustmentOptions& options);

/// Pose-only refinement after resection: minimises the robustified reprojection error of the
/// 2D-3D correspondences `inliers` over the world -> camera pose (q_cw, t_cw), points fixed.
/// Returns false when Ceres found no usable solution (pose unchanged then).
bool refineAbsolutePose(const scene::Camera& camera, const std::vector<Eigen::Vector3d>& points,
                        const std::vector<Eigen::Vector2d>& pixels,
                        const std::vector<uint32_t>& inliers,
                        const BundleAdjustmentOptions& options, Eigen::Quaterniond& q_cw,
                        Eigen::Vector3d& t_cw);

}  // namespace auv::recon::sfm
