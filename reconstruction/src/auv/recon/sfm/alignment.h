#pragma once
// Similarity transforms between a reconstruction's frame and another one (ground truth, the
// vehicle's navigation): Umeyama's closed form (IEEE PAMI 13(4), 1991) through Eigen::umeyama.

#include <map>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "auv/recon/scene/reconstruction.h"

namespace auv::recon::sfm {

/// x' = scale * rotation * x + translation.
struct Similarity {
  double scale = 1;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Eigen::Vector3d apply(const Eigen::Vector3d& x) const {
    return scale * rotation * x + translation;
  }
};

/// Least-squares similarity mapping `from` onto `to` (same size, >= 3 points, not collinear);
/// nullopt when degenerate. `with_scale` false: a rigid transform (scale 1).
std::optional<Similarity> estimateSimilarity(const std::vector<Eigen::Vector3d>& from,
                                             const std::vector<Eigen::Vector3d>& to,
                                             bool with_scale = true);

/// Moves a whole reconstruction (points, camera poses) by `s`.
void transformReconstruction(const Similarity& s, scene::Reconstruction& reconstruction);

/// How far camera poses are from reference poses: positions after the similarity that best
/// aligns the camera centres, orientations after the rotation that best aligns the
/// orientations (centres along a line leave the roll about it to the noise). Images matched
/// by id; those missing in either are ignored.
struct PoseErrors {
  size_t images = 0;
  double mean_position = 0, median_position = 0, max_position = 0;  ///< reference units
  double mean_rotation_deg = 0, max_rotation_deg = 0;
  Similarity alignment;
};
/// nullopt when fewer than 3 common images or degenerate centres.
std::optional<PoseErrors> poseErrorsAfterAlignment(
    const std::map<uint32_t, scene::Image>& estimated,
    const std::map<uint32_t, scene::Image>& reference);

}  // namespace auv::recon::sfm
