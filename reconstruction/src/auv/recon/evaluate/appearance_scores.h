#pragma once
// The appearance change of a comparison (compare's colour difference, change/appearance.h)
// scored against the simulator's truth, as change_scores.h scores the shape's: which albedo
// regions (a colour change, no shape change) were found, which colour clusters are true, and
// how much stable surface was called recoloured (README.md, "Change against the truth").
//
// A colour cluster on a geometric region's truth is *explained by geometry*, not false: a
// fallen block also brings its own colour, and compare compares colours only where the shape
// did not change significantly, so the block's foot and edges show up as colour change.

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "auv/recon/change/appearance.h"
#include "auv/recon/evaluate/change_scores.h"
#include "auv/recon/evaluate/change_truth.h"

namespace auv::recon::evaluate {

/// One albedo region against the colour change.
struct AppearanceRegionScore {
  /// detected, missed, not_measured (too little of it near a core point with a colour);
  /// geometric: a shape change, scored by change_scores.h
  std::string status;
  size_t truth_points = 0;
  size_t measured_points = 0;    ///< near a core point whose colour was compared (in the region)
  size_t hit_points = 0;         ///< near an appearance-significant one
  std::vector<size_t> clusters;  ///< the true colour clusters assigned to it
};

/// One cluster of appearance-significant core points (as compare forms them) against the truth.
struct AppearanceClusterScore {
  change::AppearanceCluster cluster;  ///< world frame
  /// true (on an albedo region), explained_by_geometry (on a geometric region's truth instead),
  /// false, outside_region
  std::string verdict;
  /// The region most of its points reach: an albedo one unless explained_by_geometry or on
  /// none; -1 when on no truth
  int region = -1;
  size_t albedo_points = 0;     ///< its core points near an albedo region's truth
  size_t geometric_points = 0;  ///< near a geometric region's truth
};

struct AppearanceScores {
  std::vector<AppearanceRegionScore> regions;  ///< per truth region
  std::vector<AppearanceClusterScore> clusters;
  /// Colour-measured core points near no true point of any region; `fraction` is of those in
  /// scored clusters (lone significant points are the threshold's expected tail).
  StableScore stable;
  size_t colour_measured = 0;  ///< core points whose colour was compared (in the region)
  size_t detected = 0, missed = 0, not_measured = 0;
  size_t true_clusters = 0, false_clusters = 0, explained_by_geometry = 0, outside_region = 0;
  /// detected / (detected + missed); also counting the not measured; NaN when none.
  double recall_measured = 0, recall_all = 0;
  double precision = 0;  ///< true / (true + false) clusters; NaN when none
};

/// Scores the colour change of `change` against `truth`, both in the world frame, with the
/// geometric scoring's match radius, fractions and minimum cluster area (without
/// change.hasAppearance() no colour was measured: every albedo region not_measured).
AppearanceScores scoreAppearance(const ChangeTruth& truth, const WorldChange& change,
                                 const ChangeScoreOptions& options);

/// The `appearance` object of evaluation.json's `change` section (albedo regions by name).
nlohmann::json appearanceScoresJson(const AppearanceScores& scores, const ChangeTruth& truth);

}  // namespace auv::recon::evaluate
