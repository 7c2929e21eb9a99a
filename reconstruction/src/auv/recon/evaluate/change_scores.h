#pragma once
// A comparison of two surveys (`auv recon compare`, change/compare_stage.h) scored against the
// simulator's truth of what changed (change_truth.h), both in the world frame: which true
// regions were found, which found regions are true, how much stable surface was called
// changed, and how well the distances and volumes of the found ones agree (README.md, "Change
// against the truth").
//
// A core point measures the surface along its normal from survey 1's surface (the core point)
// to survey 2's (core point + distance x normal); a true changed point lies on one of them
// (gained: the later surface, lost: the earlier). So a core point *reaches* a true point when
// the segment between the two lies within match_radius_m of it: a 1 m block's top is reached
// from the core points on the seabed under it.

#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "auv/recon/change/clusters.h"
#include "auv/recon/evaluate/change_truth.h"

namespace auv::recon::evaluate {

struct ChangeScoreOptions {
  /// m: true regions whose largest |distance| is smaller are not asked for (recall).
  double min_magnitude_m = 0.10;
  /// m: a core point's segment this near a true point reaches it (~1.5 core spacings).
  double match_radius_m = 0.3;
  /// A region is detected when this share of its measured true points is reached by
  /// significant core points; a cluster is true when this share of its points reach the truth.
  double min_hit_fraction = 0.3;
  /// A region with a smaller share of its true points reached by measured core points was not
  /// measured: reported apart from the missed ones.
  double min_measured_fraction = 0.1;
  /// m²: clusters smaller are not scored; 0 = compare's own minimum.
  double min_cluster_area_m2 = 0;

  /// Throws OptionError naming the field and its value.
  void check() const;
};

/// The comparison's core points in the world frame.
struct WorldChange {
  std::vector<Eigen::Vector3d> points;   ///< core points (on survey 1's surface)
  std::vector<Eigen::Vector3d> normals;  ///< unit, the side + distances point to
  std::vector<double> distances;         ///< m; NaN: not measured
  /// m, each point's level of detection at the distances' scale; empty in an older compare's
  /// file (then no region is tested family-wise)
  std::vector<double> levels_of_detection;
  /// What the regions are made of: compare's `detection_significant` at two scales, else its
  /// `significant`.
  std::vector<char> significant;
  /// At two scales, the coarse distances the regions were found with (min_change_m); the
  /// regions are measured with `distances`. Empty at one scale.
  std::vector<double> detection_distances;
  /// At two scales: compare's `significant` at the measuring scale (what regions grow into).
  std::vector<char> measuring_significant;
  /// Per core point: compare's colour difference ΔE*ab (NaN: colours not compared) and whether
  /// it is significant. Both empty when changes.ply has none (an older compare).
  std::vector<double> delta_e;
  std::vector<char> appearance_significant;
  /// Per core point: in the well-imaged region of both visits; empty = everywhere.
  std::vector<char> in_region;
  double core_spacing_m = 0.2;        ///< m, each core point stands for its square
  double min_cluster_area_m2 = 0.05;  ///< m², compare's minimum
  double min_change_m = 0.0;          ///< m, compare's smallest change of interest
  double volume_margin_m = 0.0;       ///< m, compare's rim of a region's volume (clusters.h)
  double region_confidence = 0.0;     ///< compare's family-wise test of regions (0: off)
  bool grow_regions = false;          ///< compare's growth at the measuring scale
  double region_footprint_m2 = 0.0;   ///< m², one independent measurement's area
  double level_of_detection_z = 1.96;

  bool inRegion(size_t i) const { return in_region.empty() || in_region[i]; }
  bool measured(size_t i) const { return distances[i] == distances[i]; }
  bool hasAppearance() const { return !appearance_significant.empty(); }
  bool colourMeasured(size_t i) const { return hasAppearance() && delta_e[i] == delta_e[i]; }
};

/// One true region against the comparison.
struct RegionScore {
  /// detected, missed, not_measured (too little of it reached by measured core points),
  /// below_min_magnitude, appearance (albedo: not geometric)
  std::string status;
  size_t truth_points = 0;
  size_t measured_points = 0;      ///< reached by a measured core point (in the region)
  size_t hit_points = 0;           ///< reached by a significant one
  std::vector<size_t> clusters;    ///< the true clusters assigned to it
  change::ChangeCluster measured;  ///< its clusters together (area, distances, volumes)
};

/// One cluster of significant core points (as compare forms them) against the truth.
struct ClusterScore {
  change::ChangeCluster cluster;  ///< world frame
  /// true (on a geometric region), false, appearance (on an albedo region), outside_region
  std::string verdict;
  int region = -1;        ///< the region most of its reaching points reach
  size_t hit_points = 0;  ///< its core points reaching a true point
};

/// Significant change where nothing changed (of the shape here; of the colour in
/// appearance_scores.h).
struct StableScore {
  size_t measured = 0;                 ///< measured core points farther than match radius
  size_t significant = 0;              ///< of them significant
  size_t significant_in_clusters = 0;  ///< of those in a scored cluster
  /// significant / measured; of the colour: significant_in_clusters / measured
  double fraction = 0;
  double area_m2 = 0, cluster_area_m2 = 0;  ///< counts x core spacing²
};

/// The `stable` section of evaluation.json (the shape's and the colour's alike).
nlohmann::json stableJson(const StableScore& stable);

struct ChangeScores {
  std::vector<RegionScore> regions;  ///< per truth region
  std::vector<ClusterScore> clusters;
  StableScore stable;
  size_t detected = 0, missed = 0, not_measured = 0;
  size_t true_clusters = 0, false_clusters = 0;
  /// detected / (detected + missed); also counting the not measured as missed; NaN when none.
  double recall_measured = 0, recall_all = 0;
  double precision = 0;  ///< true / (true + false) clusters; NaN when none
};

/// Scores `change` against `truth` (both in the world frame).
ChangeScores scoreChanges(const ChangeTruth& truth, const WorldChange& change,
                          const ChangeScoreOptions& options);

/// The scores as written to evaluation.json's `change` section (regions by name).
nlohmann::json changeScoresJson(const ChangeScores& scores, const ChangeTruth& truth,
                                const ChangeScoreOptions& options);

}  // namespace auv::recon::evaluate
