#pragma once
// The changed regions of a comparison: significant M3C2 core points joined into clusters,
// each with its area, distances and the volume gained and lost.
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "auv/recon/change/m3c2.h"

namespace auv::recon::change {

struct ChangeCluster {
  std::vector<size_t> core_points;  ///< indices into the comparison's core points
  double area_m2 = 0.0;             ///< core points × spacing²
  double mean_distance_m = 0.0;
  double max_abs_distance_m = 0.0;  ///< the largest |distance|, signed as measured
  /// Sum of the positive distances × spacing² (with the margin's net change, see below).
  double volume_gained_m3 = 0.0;
  double volume_lost_m3 = 0.0;  ///< the same of the negative distances (as > 0)
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  double mean_level_of_detection_m = 0.0;  ///< over the measured points
  /// The region's mean change in standard errors: z |mean distance| / mean level of detection,
  /// z that of the levels (1.96); the whole region taken as one measurement (RegionOptions).
  double significance_z = 0.0;
};

/// How significant core points become the regions compare reports (compare and evaluate
/// alike: findRegions).
struct RegionOptions {
  double spacing_m = 0.2;  ///< each core point stands for spacing² of surface
  double link_m = 0.3;     ///< significant points within this of each other: one region
  double min_area_m2 = 0.05;
  /// m: regions where less than min_area_m2 changed this much are dropped (not of interest)
  double min_change_m = 0.0;
  double volume_margin_m = 0.0;  ///< m: the rim whose net change a region's volume takes
  /// > 0: a region is kept only when its mean change is significant at this confidence
  /// *family-wise*, over every independent measurement of the site. Each core point's level of
  /// detection holds at 95 % for that point alone; a site holds M = measured area / footprint_m2
  /// independent ones, so ~5 % of them pass by chance and, where two reconstructions disagree
  /// over a patch, neighbours pass together: a false region. The region is tested as one
  /// measurement (its points share the reconstructions' errors, so averaging them proves
  /// nothing more) against the Bonferroni bound: z >= Φ⁻¹(1 − (1 − confidence) / 2M).
  double family_confidence = 0.0;
  double footprint_m2 = 0.0;  ///< one independent measurement: the cylinder's cross-section
  double level_of_detection_z = 1.96;  ///< the z the levels of detection were computed at
  /// Two scales: a region found at the detection scale also takes the core points linked to it
  /// that are significant at the measuring scale with its sign (hysteresis, as Canny's edges:
  /// the coarse scale seeds, the fine one extends). The coarse cylinders average a small
  /// block's edges with the floor around it; the fine ones see them.
  bool grow_at_measuring_scale = false;
};

/// The z a region's mean change must reach (RegionOptions::family_confidence) on a site of
/// `measured_points` core points; 0 when the test is off.
double familyWiseZ(const RegionOptions& options, size_t measured_points);

/// A region as report.json lists it (area, core points, distances, volumes, centroid).
nlohmann::json clusterJson(const ChangeCluster& cluster);

/// The flagged points joined into groups: points within `link_m` of each other are one group
/// (indices into `points`, each group sorted).
std::vector<std::vector<size_t>> linkFlagged(const std::vector<Eigen::Vector3d>& points,
                                             const std::vector<char>& flagged, double link_m);

/// Significant core points within `link_m` of each other form one cluster; each core point
/// stands for `spacing_m`² of surface. Clusters smaller than `min_area_m2` are dropped (noise
/// at the level of detection), and those whose points changed by at least `min_change_m` (the
/// smallest change of interest) cover less than `min_area_m2`: significant, but not a change
/// anyone asked about. Sorted by area, largest first.
///
/// M3C2 averages over its cylinder, so a change shows, weakened, up to the cylinder's radius
/// beyond the points that pass the level of detection, and a volume summed over those alone
/// misses that rim. With `volume_margin_m` > 0, each cluster's volume on its side (gained when
/// its mean distance is positive, else lost) also takes the net distance of the measured core
/// points within that margin that belong to no cluster (each to the nearest cluster): on
/// unchanged ground their noise cancels.
std::vector<ChangeCluster> clusterChanges(const std::vector<Eigen::Vector3d>& core_points,
                                          const std::vector<M3C2Point>& comparison,
                                          double spacing_m, double link_m, double min_area_m2,
                                          double min_change_m = 0.0, double volume_margin_m = 0.0);

/// For a comparison at two scales: each cluster's distances and volumes again from
/// `measurement` (the same core points compared at the finer scale; points it did not measure
/// left out), with the rim's net change within `volume_margin_m` as in clusterChanges. Points,
/// area and centroid stay: the coarse scale found the region, the fine one measures it.
void remeasureClusters(std::vector<ChangeCluster>& clusters,
                       const std::vector<Eigen::Vector3d>& core_points,
                       const std::vector<M3C2Point>& measurement, double spacing_m,
                       double volume_margin_m);

/// The regions as compare reports them: found in `detection` (clusterChanges), grown at the
/// measuring scale when asked, and measured in `measurement` when given (two scales), else in
/// `detection` itself; those that fail the
/// family-wise test dropped (before the rims are shared out); the volumes take the rim.
std::vector<ChangeCluster> findRegions(const std::vector<Eigen::Vector3d>& core_points,
                                       const std::vector<M3C2Point>& detection,
                                       const std::vector<M3C2Point>* measurement,
                                       const RegionOptions& options);

}  // namespace auv::recon::change
