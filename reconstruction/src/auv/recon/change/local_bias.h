#pragma once
// The slowly varying part of an M3C2 comparison of two photogrammetric surveys. Each survey is
// reconstructed on its own drifting navigation, so after the best rigid co-registration the two
// models still differ by a smooth deformation (the real canyon pair without change: one wall
// 7 cm off, distances +1.8 cm on average, 8.9 % of the core points "significant"). That part is
// the registration's error, not a change of the site: it is estimated as the median distance of
// the measured core points within `radius_m` — a change smaller than that neighbourhood does not
// move the median — and taken out of each distance. What is left over the whole site gives the
// registration error of the level of detection (robust sigma: 1.4826 × MAD).
#include <vector>

#include <Eigen/Core>

#include "auv/recon/change/m3c2.h"

namespace auv::recon::change {

struct LocalBias {
  std::vector<double> bias;        ///< per core point, m (0 where not measured)
  double residual_sigma_m = 0.0;   ///< robust spread of the corrected distances
  double median_abs_bias_m = 0.0;  ///< how far the surveys were bent apart, typically
};

/// Subtracts from each measured distance the median distance of the measured core points
/// within `radius_m` (itself included; unchanged where fewer than `min_neighbours`).
LocalBias removeLocalBias(const std::vector<Eigen::Vector3d>& core_points,
                          std::vector<M3C2Point>& comparison, double radius_m,
                          int min_neighbours = 20);

/// Recomputes every measured point's level of detection and significance with
/// `registration_error_m` (M3C2's Eq. (1): LoD = z (sqrt(s1²/n1 + s2²/n2) + reg)).
void applyLevelOfDetection(std::vector<M3C2Point>& comparison, double registration_error_m,
                           double confidence_z);

}  // namespace auv::recon::change
