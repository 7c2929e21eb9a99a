#pragma once
// Co-registration of two surveys of one site on their *stable* surfaces: what changed between
// the visits must not pull the alignment, or the change would be partly absorbed into it.
//
// From a coarse transform (the navigation frames, identity when both surveys were aligned to
// the same navigation), rounds of robust point-to-plane ICP (Open3D, Tukey loss) on the points
// of survey 2 still deemed stable; after each round the points farther than stable_threshold_m
// from survey 1's surface are set aside as changed. The result says how much overlapped, how
// much was stable and the RMS residual on the stable points: the registration error M3C2's
// level of detection needs (m3c2.h).
#include <stdexcept>
#include <vector>

#include <Eigen/Core>

namespace auv::recon::change {

struct CoregistrationOptions {
  double voxel_m = 0.1;  ///< both clouds are thinned to one point per voxel for the ICP
  /// m, farthest correspondence of the first round (what the coarse transform may be off by).
  double max_correspondence_m = 1.0;
  /// m, a point of survey 2 farther than this from survey 1's surface is changed, not stable;
  /// also the Tukey loss's scale.
  double stable_threshold_m = 0.1;
  int rounds = 4;                    ///< ICP runs, each on the points still stable
  int icp_iterations = 50;           ///< per round
  double min_overlap = 0.2;          ///< share of survey 2 within max_correspondence_m of survey 1
  double min_stable_fraction = 0.3;  ///< share of the overlapping points that must be stable

  /// Throws OptionError naming the field and its value.
  void check() const;
};

struct CoregistrationResult {
  Eigen::Matrix4d transform = Eigen::Matrix4d::Identity();  ///< survey 2 -> survey 1's frame
  double rms_m = 0.0;  ///< point-to-plane residual over the stable points
  double overlap = 0.0;
  double stable_fraction = 0.0;
  /// Per point of survey 2 (input order): within stable_threshold_m of survey 1's surface after
  /// the alignment.
  std::vector<bool> stable;
  int rounds = 0;
};

/// Not enough common, unchanged surface to align on: the message names the overlap or the
/// stable fraction found and the option it fell short of.
class CoregistrationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Aligns `cloud2` to `cloud1` from `initial` (cloud 2 -> cloud 1). Throws OptionError on bad
/// options and CoregistrationError when the clouds do not overlap enough or too little of the
/// overlap is stable.
CoregistrationResult coregister(const std::vector<Eigen::Vector3d>& cloud1,
                                const std::vector<Eigen::Vector3d>& cloud2,
                                const Eigen::Matrix4d& initial,
                                const CoregistrationOptions& options);

}  // namespace auv::recon::change
