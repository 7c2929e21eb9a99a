#pragma once
// Similarity alignment of a reconstruction to the ground truth from camera poses, and the
// camera pose errors after it.
//
// A reconstruction from images alone is known up to a similarity (paper section 3.4: "defined
// only up to scale"; section 4.3 had to estimate the scale by hand). We estimate it from the
// registered images' poses against their true poses: Umeyama's least-squares similarity
// (Eigen::umeyama; Umeyama, PAMI 1991) on the camera centres plus, for each image, two points
// `axis_length_m` along its optical axis and its x axis, so a nearly straight trajectory (a
// canyon traverse at constant depth) still fixes the rotation about its line. Robust to a
// minority of wrongly registered images: least median of squares over minimal samples
// (Rousseeuw, JASA 1984), inliers from the robust scale, then Umeyama on the inliers.

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace auv::recon::evaluate {

/// x_truth = scale * rotation * x_reconstruction + translation.
struct Similarity {
  double scale = 1.0;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Eigen::Vector3d apply(const Eigen::Vector3d& x) const {
    return scale * (rotation * x) + translation;
  }
  Eigen::Matrix4d matrix() const;
  Similarity inverse() const;
  /// A world -> camera rotation of the reconstruction expressed in the truth's frame.
  Eigen::Matrix3d applyToCameraRotation(const Eigen::Matrix3d& rotation_cw) const {
    return rotation_cw * rotation.transpose();
  }
};

/// One image seen by both: its pose in the reconstruction and its true pose (world -> camera
/// rotations, centres in the world).
struct PosePair {
  std::string name;
  Eigen::Vector3d center_estimate, center_truth;
  Eigen::Matrix3d rotation_estimate_cw, rotation_truth_cw;
};

struct AlignmentOptions {
  double axis_length_m = 1.0;  ///< m (truth units): length of the axis points; 0 = centres only
  int max_trials = 1000;       ///< LMedS samples (all pairs when fewer)
  double inlier_sigmas = 3.0;  ///< inlier: residual <= inlier_sigmas x robust sigma
  double min_inlier_m = 0.05;  ///< m: residuals below this are always inliers
  size_t min_images = 3;       ///< fewer matched images: TOO_FEW_IMAGES
  uint64_t seed = 1;           ///< sampling

  /// Throws OptionError naming the field and value.
  void check() const;
};

enum class AlignmentStatus { SUCCESS, TOO_FEW_IMAGES, DEGENERATE };

struct AlignmentResult {
  AlignmentStatus status = AlignmentStatus::TOO_FEW_IMAGES;
  Similarity similarity;
  std::vector<bool> inliers;  ///< per pose pair
  size_t num_inliers = 0;
  double robust_sigma_m = 0;  ///< m, from the median residual
  std::string message;        ///< why it failed, with the numbers
};

/// Estimates the similarity reconstruction -> truth. Throws OptionError for bad options.
AlignmentResult alignToTruth(const std::vector<PosePair>& pairs, const AlignmentOptions& options);

/// Camera pose errors after alignment.
struct PoseErrors {
  std::vector<double> position_m;    ///< per pair: |aligned centre - true centre|
  std::vector<double> rotation_deg;  ///< per pair: angle of R_true R_aligned^T
  double mean_position_m = 0, median_position_m = 0, rms_position_m = 0, max_position_m = 0;
  double mean_rotation_deg = 0, median_rotation_deg = 0, max_rotation_deg = 0;
};

PoseErrors poseErrors(const std::vector<PosePair>& pairs, const Similarity& similarity);

/// Median of a copy of `values` (0 when empty).
double median(std::vector<double> values);

}  // namespace auv::recon::evaluate
