#include "auv/recon/evaluate/change_scores.h"

#include <cmath>
#include <limits>

#include "auv/recon/common/stage_error.h"
#include "auv/recon/evaluate/change_reach.h"

using nlohmann::json;

namespace auv::recon::evaluate {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string regionStatus(const TrueChangeRegion& region, const RegionTally& tally,
                         const ChangeScoreOptions& options) {
  if (!region.geometric) return "appearance";
  if (region.magnitude() < options.min_magnitude_m) return "below_min_magnitude";
  return measuredStatus(tally, options);
}

/// Each cluster: on which region, if any, and whether it counts as true, false or neither.
std::vector<ClusterScore> scoreClusters(const ChangeTruth& truth, const WorldChange& change,
                                        const Reach& reach, const ChangeScoreOptions& options) {
  const bool two_scales = !change.detection_distances.empty();
  std::vector<change::M3C2Point> comparison(change.points.size()), fine;
  for (size_t i = 0; i < comparison.size(); ++i) {
    comparison[i].normal = change.normals[i];
    comparison[i].distance = change.distances[i];
    comparison[i].significant = change.significant[i] && change.measured(i);
    if (!change.levels_of_detection.empty())
      comparison[i].level_of_detection = change.levels_of_detection[i];
  }
  if (two_scales) {
    fine = comparison;
    for (size_t i = 0; i < fine.size(); ++i) {
      fine[i].significant = i < change.measuring_significant.size() &&
                            change.measuring_significant[i] && fine[i].valid();
    }
    for (size_t i = 0; i < comparison.size(); ++i) {
      comparison[i].distance = change.detection_distances[i];
      comparison[i].significant = change.significant[i] && comparison[i].valid();
    }
  }
  // Joined, measured and tested as compare does (clusters.h): within 1.5 core spacings; at two
  // scales found with the coarse distances and measured with the fine ones.
  change::RegionOptions regions;
  regions.spacing_m = change.core_spacing_m;
  regions.link_m = 1.5 * change.core_spacing_m;
  regions.min_area_m2 =
      options.min_cluster_area_m2 > 0 ? options.min_cluster_area_m2 : change.min_cluster_area_m2;
  regions.min_change_m = change.min_change_m;
  regions.volume_margin_m = change.volume_margin_m;
  regions.grow_at_measuring_scale = change.grow_regions;
  if (!change.levels_of_detection.empty()) {
    regions.family_confidence = change.region_confidence;
    regions.footprint_m2 = change.region_footprint_m2;
    regions.level_of_detection_z = change.level_of_detection_z;
  }
  const std::vector<change::ChangeCluster> clusters =
      change::findRegions(change.points, comparison, two_scales ? &fine : nullptr, regions);
  std::vector<ClusterScore> scores;
  for (const change::ChangeCluster& cluster : clusters) {
    ClusterScore score;
    score.cluster = cluster;
    const ClusterReach on = reachOfCluster(cluster.core_points, reach.core_region);
    score.hit_points = on.hit_points;
    score.region = on.region;
    if (mostlyOutsideRegion(change, cluster.core_points)) {
      score.verdict = "outside_region";
    } else if (enoughHits(score.hit_points, cluster.core_points.size(), options)) {
      score.verdict =
          truth.regions[static_cast<size_t>(score.region)].geometric ? "true" : "appearance";
    } else {
      score.verdict = "false";
    }
    scores.push_back(std::move(score));
  }
  return scores;
}

/// The clusters assigned to a region, taken together.
change::ChangeCluster combine(const std::vector<ClusterScore>& clusters,
                              const std::vector<size_t>& chosen) {
  change::ChangeCluster sum;
  size_t points = 0;
  for (size_t k : chosen) {
    const change::ChangeCluster& c = clusters[k].cluster;
    const double n = static_cast<double>(c.core_points.size());
    sum.area_m2 += c.area_m2;
    sum.mean_distance_m += c.mean_distance_m * n;
    sum.centroid += c.centroid * n;
    if (std::abs(c.max_abs_distance_m) > std::abs(sum.max_abs_distance_m)) {
      sum.max_abs_distance_m = c.max_abs_distance_m;
    }
    sum.volume_gained_m3 += c.volume_gained_m3;
    sum.volume_lost_m3 += c.volume_lost_m3;
    points += c.core_points.size();
  }
  if (points > 0) {
    sum.mean_distance_m /= static_cast<double>(points);
    sum.centroid /= static_cast<double>(points);
  }
  return sum;
}

StableScore scoreStable(const WorldChange& change, const Reach& reach,
                        const std::vector<ClusterScore>& clusters) {
  std::vector<char> stable_points(change.points.size(), 0);
  for (size_t i = 0; i < change.points.size(); ++i) {
    stable_points[i] = change.inRegion(i) && change.measured(i) && reach.core_region[i] < 0;
  }
  StableScore stable = tallyStable(change, stable_points, change.significant,
                                   inScoredClusters(change.points.size(), clusters));
  stable.fraction = ratio(stable.significant, stable.measured);
  return stable;
}

/// (measured - true) / true; NaN when the truth is 0.
double relativeError(double measured, double truth) {
  return truth > 0 ? (measured - truth) / truth : kNaN;
}

json regionJson(const TrueChangeRegion& truth, const RegionScore& score) {
  json j = {{"name", truth.name},
            {"change", truth.change},
            {"type", truth.type},
            {"status", score.status},
            {"magnitude_m", truth.magnitude()},
            {"truth_points", score.truth_points},
            {"measured_fraction", finiteOrNull(ratio(score.measured_points, score.truth_points))},
            {"hit_fraction", finiteOrNull(ratio(score.hit_points, score.measured_points))},
            {"clusters", score.clusters}};
  if (score.clusters.empty()) return j;
  const change::ChangeCluster& m = score.measured;
  // The side of the change the truth has most of: a block's gained or lost volume.
  const bool gained = truth.volume_gained_m3 >= truth.volume_lost_m3;
  const double true_volume = gained ? truth.volume_gained_m3 : truth.volume_lost_m3;
  const double volume = gained ? m.volume_gained_m3 : m.volume_lost_m3;
  j["measured"] = change::clusterJson(m);
  j["measured"].erase("core_points");
  j["errors"] = {{"mean_distance_m", m.mean_distance_m - truth.mean_distance_m},
                 {"max_distance_m", m.max_abs_distance_m - truth.max_distance_m},
                 {"volume_side", gained ? "gained" : "lost"},
                 {"volume_true_m3", true_volume},
                 {"volume_measured_m3", volume},
                 {"volume_relative", finiteOrNull(relativeError(volume, true_volume))},
                 {"volume_gained_relative",
                  finiteOrNull(relativeError(m.volume_gained_m3, truth.volume_gained_m3))},
                 {"volume_lost_relative",
                  finiteOrNull(relativeError(m.volume_lost_m3, truth.volume_lost_m3))}};
  if (truth.isBlock()) {
    const double relative = relativeError(volume, true_volume);
    j["errors"]["volume_within_20_percent"] = std::isfinite(relative) && std::abs(relative) <= 0.2;
  }
  return j;
}

}  // namespace

void ChangeScoreOptions::check() const {
  AUV_RECON_CHECK_OPTION(min_magnitude_m >= 0, min_magnitude_m, "must be >= 0 m");
  AUV_RECON_CHECK_OPTION(match_radius_m > 0, match_radius_m, "must be > 0 m");
  AUV_RECON_CHECK_OPTION(min_hit_fraction > 0 && min_hit_fraction <= 1, min_hit_fraction,
                         "must be in (0, 1]");
  AUV_RECON_CHECK_OPTION(min_measured_fraction >= 0 && min_measured_fraction <= 1,
                         min_measured_fraction, "must be in [0, 1]");
  AUV_RECON_CHECK_OPTION(min_cluster_area_m2 >= 0, min_cluster_area_m2,
                         "must be >= 0 m² (0: compare's own)");
}

ChangeScores scoreChanges(const ChangeTruth& truth, const WorldChange& change,
                          const ChangeScoreOptions& options) {
  options.check();
  std::vector<char> measured(change.points.size());
  for (size_t i = 0; i < measured.size(); ++i) measured[i] = change.measured(i);
  const Reach reach =
      reachTruth(truth, change, measured, change.significant, options.match_radius_m);
  const std::vector<RegionTally> tally = tallyRegions(truth, reach);
  ChangeScores scores;
  scores.regions.resize(truth.regions.size());
  for (size_t k = 0; k < truth.regions.size(); ++k) {
    scores.regions[k].truth_points = tally[k].truth_points;
    scores.regions[k].measured_points = tally[k].measured_points;
    scores.regions[k].hit_points = tally[k].hit_points;
  }
  scores.clusters = scoreClusters(truth, change, reach, options);
  for (size_t k = 0; k < scores.clusters.size(); ++k) {
    const ClusterScore& c = scores.clusters[k];
    if (c.verdict == "true") scores.regions[static_cast<size_t>(c.region)].clusters.push_back(k);
    scores.true_clusters += c.verdict == "true" ? 1 : 0;
    scores.false_clusters += c.verdict == "false" ? 1 : 0;
  }
  for (size_t k = 0; k < truth.regions.size(); ++k) {
    RegionScore& r = scores.regions[k];
    r.status = regionStatus(truth.regions[k], tally[k], options);
    r.measured = combine(scores.clusters, r.clusters);
    scores.detected += r.status == "detected" ? 1 : 0;
    scores.missed += r.status == "missed" ? 1 : 0;
    scores.not_measured += r.status == "not_measured" ? 1 : 0;
  }
  scores.recall_measured = ratio(scores.detected, scores.detected + scores.missed);
  scores.recall_all = ratio(scores.detected, scores.detected + scores.missed + scores.not_measured);
  scores.precision = ratio(scores.true_clusters, scores.true_clusters + scores.false_clusters);
  scores.stable = scoreStable(change, reach, scores.clusters);
  return scores;
}

json stableJson(const StableScore& s) {
  return {{"core_points_measured", s.measured},
          {"core_points_significant", s.significant},
          {"core_points_significant_in_clusters", s.significant_in_clusters},
          {"false_fraction", finiteOrNull(s.fraction)},
          {"false_area_m2", s.area_m2},
          {"false_cluster_area_m2", s.cluster_area_m2}};
}

json changeScoresJson(const ChangeScores& scores, const ChangeTruth& truth,
                      const ChangeScoreOptions& options) {
  json regions = json::array();
  for (size_t k = 0; k < truth.regions.size(); ++k) {
    regions.push_back(regionJson(truth.regions[k], scores.regions[k]));
  }
  json clusters = json::array();
  for (const ClusterScore& c : scores.clusters) {
    json j = change::clusterJson(c.cluster);
    j["verdict"] = c.verdict;
    j["region"] =
        c.region >= 0 ? json(truth.regions[static_cast<size_t>(c.region)].name) : json(nullptr);
    j["hit_fraction"] = finiteOrNull(ratio(c.hit_points, c.cluster.core_points.size()));
    clusters.push_back(j);
  }
  return {{"regions_scored",
           {{"detected", scores.detected},
            {"missed", scores.missed},
            {"not_measured", scores.not_measured},
            {"recall_measured", finiteOrNull(scores.recall_measured)},
            {"recall_all", finiteOrNull(scores.recall_all)}}},
          {"clusters_scored",
           {{"true", scores.true_clusters},
            {"false", scores.false_clusters},
            {"precision", finiteOrNull(scores.precision)}}},
          {"stable", stableJson(scores.stable)},
          {"regions", regions},
          {"clusters", clusters},
          {"options",
           {{"min_magnitude_m", options.min_magnitude_m},
            {"match_radius_m", options.match_radius_m},
            {"min_hit_fraction", options.min_hit_fraction},
            {"min_measured_fraction", options.min_measured_fraction},
            {"min_cluster_area_m2", options.min_cluster_area_m2}}}};
}

}  // namespace auv::recon::evaluate
