#pragma once
// `auv recon compare <survey-1> <survey-2>`: what changed at the site between two surveys
// (issue 21). Both dense clouds (dense/fused.ply) are co-registered on their stable surfaces
// (coregistration.h), compared by M3C2 at core points thinned from survey 1's cloud (m3c2.h),
// the significant changes clustered (clusters.h), and written into survey 2:
//
//   change/changes.ply     core points: normal, distance, level_of_detection, significant,
//                          and the appearance change (appearance.h): delta_e, appearance;
//                          at two scales also detection_distance, detection_level_of_detection,
//                          detection_significant (what the regions are made of)
//   change/change_map.png  the top-down change map (change_map.h)
//   change/mesh_change.ply survey 2's mesh/mesh.ply, vertices coloured by the change
//   change/change_view.png that mesh seen from above and to the side (change_view.h)
//   change/report.json     the registration, the counts, every cluster (area, distances,
//                          volumes, centroid), the appearance change (colour normalisation,
//                          threshold, its clusters); also the `compare` section of report.json
//
// Not chained by `auv recon run`: it needs two surveys.
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "auv/recon/change/appearance.h"
#include "auv/recon/change/coregistration.h"
#include "auv/recon/change/m3c2.h"
#include "auv/recon/common/stage.h"
#include "auv/recon/common/survey.h"

namespace auv::recon {
class OptionSet;
}

namespace auv::recon::change {

struct CompareOptions {
  std::string later;  ///< survey 2 (the positional after survey 1); the outputs go there
  CoregistrationOptions coregistration;
  M3C2Options m3c2;
  AppearanceOptions appearance;
  double core_spacing_m = 0.2;  ///< survey 1's cloud thinned to one core point per voxel
  /// m: the two surveys' smooth deformation, the median distance within this radius, is taken
  /// out of the distances (local_bias.h); 0 = off. Changes must be smaller than about half
  /// this neighbourhood's area.
  double bias_radius_m = 4.0;
  /// > 1: the regions are found by M3C2 at this multiple of d and D (its averages over the
  /// larger cylinder are steadier: fewer false regions where the reconstructions disagree over
  /// a few decimetres) and measured — distances, volumes — at d and D. 1: one scale. 2 on the
  /// canyon pairs: precision 11/22 -> 13/23, false change on the control 3.15 -> 1.12 %, every
  /// fallen block's volume within 20 % (reconstruction/bench/change/README.md).
  double detection_scale = 2.0;
  /// At two scales, a region also takes the linked core points significant at the measuring
  /// scale with its sign (RegionOptions::grow_at_measuring_scale): a small block's edges.
  bool grow_regions = true;
  /// > 0: a region is kept only when its mean change is significant at this confidence over
  /// the whole site, not only at its points (clusters.h, RegionOptions::family_confidence):
  /// M3C2's per-point 95 % leaves ~5 % of a site's independent measurements passing by chance.
  /// On the canyon pairs: precision 13/23 -> 13/14, the control's false regions 9 -> 1.
  double region_confidence = 0.95;
  double min_cluster_area_m2 = 0.05;  ///< smaller clusters of significant change are dropped
  double min_change_m =
      0.1;  ///< regions with less than min_cluster_area_m2 changed this much: dropped

  void check() const;
  void bind(OptionSet& set);
};

/// Runs the comparison; `survey` is survey 1. Throws StageError("compare", ...) naming the
/// missing input (and the stage that makes it) or why the surveys cannot be aligned
/// (CoregistrationError's figures); nothing is written then.
nlohmann::json runCompare(const Survey& survey, const CompareOptions& options);

class CompareStage final : public StageWith<CompareOptions> {
 public:
  std::string name() const override { return "compare"; }
  std::string usage() const override {
    return "<survey-1> <survey-2>   what changed at the site between two surveys (M3C2)";
  }
  std::string surveyHelp() const override {
    return "the earlier survey (reads dense/fused.ply, sparse/ for the normals' side)";
  }
  bool chained() const override { return false; }
  std::vector<std::filesystem::path> inputs(const Survey& survey) const override {
    return {survey.dense()};
  }
  std::vector<std::filesystem::path> outputs(const Survey&) const override { return {}; }
  StageReport runWith(const Survey& survey, const CompareOptions& options) const override;
};

}  // namespace auv::recon::change
