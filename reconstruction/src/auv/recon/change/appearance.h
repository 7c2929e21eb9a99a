#pragma once
// Appearance change between two co-registered surveys, apart from the change of shape: at each
// core point the colour of both dense clouds nearby, survey 2's colours first brought to survey
// 1's by a per-channel gain and offset fitted on the unchanged surface (the two visits' water,
// light and camera exposure differ), then the CIE 1976 colour difference ΔE*ab. A ΔE is
// significant above a threshold set by the spread of ΔE on the rest of the site (median + k
// robust sigmas, never below `min_delta_e`); core points whose shape changed significantly are
// left to the geometric comparison (their colour differs because the surface does).
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

namespace auv::recon::change {

struct AppearanceOptions {
  double radius_m = 0.2;          ///< colours of each cloud averaged within this of a core point
  int min_points = 3;             ///< per cloud within radius_m, else not measured
  double min_delta_e = 8.0;       ///< ΔE*ab below this is never significant (just noticeable ~2.3)
  double threshold_sigmas = 3.0;  ///< significant above median + k × 1.4826 × MAD of ΔE

  /// Throws OptionError naming the field and its value.
  void check() const;
};

struct AppearanceResult {
  std::vector<double> delta_e;    ///< per core point; NaN where not measured or excluded
  std::vector<char> significant;  ///< per core point
  Eigen::Vector3d gain = Eigen::Vector3d::Ones();  ///< survey 2 RGB -> survey 1, per channel
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  double threshold = 0.0;       ///< the ΔE*ab above which a change is significant
  double median_delta_e = 0.0;  ///< over measured core points (after normalisation)
  size_t measured = 0, significant_count = 0;
};

/// `colors1`/`colors2`: RGB in [0, 1] per point of `cloud1`/`cloud2` (cloud 2 already in cloud
/// 1's frame). `exclude`: per core point, true where the shape changed (empty = none).
AppearanceResult compareAppearance(const std::vector<Eigen::Vector3d>& cloud1,
                                   const std::vector<Eigen::Vector3d>& colors1,
                                   const std::vector<Eigen::Vector3d>& cloud2,
                                   const std::vector<Eigen::Vector3d>& colors2,
                                   const std::vector<Eigen::Vector3d>& core_points,
                                   const std::vector<char>& exclude,
                                   const AppearanceOptions& options);

/// A place whose colour changed: significant core points joined (clusters.h linkFlagged).
struct AppearanceCluster {
  std::vector<size_t> core_points;
  double area_m2 = 0.0;  ///< core points × spacing²
  double mean_delta_e = 0.0, max_delta_e = 0.0;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
};

/// A region as report.json's `appearance.clusters` lists it (area, core points, ΔE, centroid).
nlohmann::json appearanceClusterJson(const AppearanceCluster& cluster);

/// Largest first; smaller than `min_area_m2` dropped.
std::vector<AppearanceCluster> clusterAppearance(const std::vector<Eigen::Vector3d>& core_points,
                                                 const AppearanceResult& result, double spacing_m,
                                                 double link_m, double min_area_m2);

/// sRGB in [0, 1] -> CIE L*a*b* (D65).
Eigen::Vector3d srgbToLab(const Eigen::Vector3d& rgb);

}  // namespace auv::recon::change
