#include "auv/recon/evaluate/appearance_scores.h"

#include <algorithm>
#include <limits>

#include "auv/recon/evaluate/change_reach.h"

using nlohmann::json;

namespace auv::recon::evaluate {
namespace {

/// Per truth region: albedo (colour only) or geometric, as region masks for reachTruth.
std::vector<char> regionsWhere(const ChangeTruth& truth, bool geometric) {
  std::vector<char> mask(truth.regions.size());
  for (size_t k = 0; k < mask.size(); ++k) mask[k] = truth.regions[k].geometric == geometric;
  return mask;
}

std::vector<AppearanceClusterScore> scoreClusters(const WorldChange& change,
                                                  const std::vector<char>& flagged,
                                                  const Reach& on_albedo, const Reach& on_shape,
                                                  const ChangeScoreOptions& options) {
  change::AppearanceResult result;
  result.delta_e = change.delta_e;
  result.delta_e.resize(change.points.size(), std::numeric_limits<double>::quiet_NaN());
  result.significant = flagged;
  const double min_area =
      options.min_cluster_area_m2 > 0 ? options.min_cluster_area_m2 : change.min_cluster_area_m2;
  // Joined as compare joins them (appearance.h): within 1.5 core spacings.
  const std::vector<change::AppearanceCluster> clusters = change::clusterAppearance(
      change.points, result, change.core_spacing_m, 1.5 * change.core_spacing_m, min_area);
  std::vector<AppearanceClusterScore> scores;
  for (const change::AppearanceCluster& cluster : clusters) {
    AppearanceClusterScore score;
    score.cluster = cluster;
    const ClusterReach albedo = reachOfCluster(cluster.core_points, on_albedo.core_region);
    const ClusterReach shape = reachOfCluster(cluster.core_points, on_shape.core_region);
    score.albedo_points = albedo.hit_points;
    score.geometric_points = shape.hit_points;
    const size_t n = cluster.core_points.size();
    if (mostlyOutsideRegion(change, cluster.core_points)) {
      score.verdict = "outside_region";
    } else if (enoughHits(albedo.hit_points, n, options)) {
      score.verdict = "true";
    } else if (enoughHits(shape.hit_points, n, options)) {
      score.verdict = "explained_by_geometry";
    } else {
      score.verdict = "false";
    }
    score.region = score.verdict == "explained_by_geometry" || albedo.region < 0 ? shape.region
                                                                                 : albedo.region;
    scores.push_back(std::move(score));
  }
  return scores;
}

/// Colour change on the surface no true region touches.
StableScore scoreStable(const WorldChange& change, const std::vector<char>& colour,
                        const std::vector<char>& flagged, const Reach& on_albedo,
                        const Reach& on_shape,
                        const std::vector<AppearanceClusterScore>& clusters) {
  std::vector<char> stable_points(change.points.size(), 0);
  for (size_t i = 0; i < change.points.size(); ++i) {
    stable_points[i] = change.inRegion(i) && colour[i] && on_albedo.core_region[i] < 0 &&
                       on_shape.core_region[i] < 0;
  }
  StableScore stable =
      tallyStable(change, stable_points, flagged, inScoredClusters(change.points.size(), clusters));
  // Lone significant points are the threshold's tail (median + k robust sigmas), which compare
  // does not report: the false share counts the clustered ones, as the campaign pools them.
  stable.fraction = ratio(stable.significant_in_clusters, stable.measured);
  return stable;
}

json regionJson(const TrueChangeRegion& truth, const AppearanceRegionScore& score,
                const std::vector<AppearanceClusterScore>& clusters) {
  json j = {{"name", truth.name},
            {"change", truth.change},
            {"type", truth.type},
            {"status", score.status},
            {"area_true_m2", truth.area_m2},
            {"truth_points", score.truth_points},
            {"measured_fraction", finiteOrNull(ratio(score.measured_points, score.truth_points))},
            {"hit_fraction", finiteOrNull(ratio(score.hit_points, score.measured_points))},
            {"clusters", score.clusters}};
  if (score.clusters.empty()) return j;
  double area = 0, weighted = 0, largest = 0;
  size_t points = 0;
  for (size_t k : score.clusters) {
    const change::AppearanceCluster& c = clusters[k].cluster;
    area += c.area_m2;
    weighted += c.mean_delta_e * static_cast<double>(c.core_points.size());
    largest = std::max(largest, c.max_delta_e);
    points += c.core_points.size();
  }
  j["measured"] = {
      {"area_m2", area},
      {"area_relative", finiteOrNull(truth.area_m2 > 0 ? (area - truth.area_m2) / truth.area_m2
                                                       : std::numeric_limits<double>::quiet_NaN())},
      {"mean_delta_e", weighted / static_cast<double>(points)},
      {"max_delta_e", largest}};
  return j;
}

}  // namespace

AppearanceScores scoreAppearance(const ChangeTruth& truth, const WorldChange& change,
                                 const ChangeScoreOptions& options) {
  options.check();
  const size_t n = change.points.size();
  std::vector<char> colour(n), flagged(n);
  for (size_t i = 0; i < n; ++i) {
    colour[i] = change.colourMeasured(i);
    flagged[i] = colour[i] && change.appearance_significant[i];
  }
  // Albedo and geometric truth reached apart: a core point near both a bleached patch and a
  // block's edge counts for the patch, whichever is nearer.
  const Reach on_albedo = reachTruth(truth, change, colour, flagged, options.match_radius_m,
                                     regionsWhere(truth, false));
  const Reach on_shape =
      reachTruth(truth, change, colour, flagged, options.match_radius_m, regionsWhere(truth, true));
  const std::vector<RegionTally> tally = tallyRegions(truth, on_albedo);

  AppearanceScores scores;
  for (size_t i = 0; i < n; ++i) scores.colour_measured += change.inRegion(i) && colour[i];
  scores.clusters = scoreClusters(change, flagged, on_albedo, on_shape, options);
  scores.regions.resize(truth.regions.size());
  for (size_t k = 0; k < scores.clusters.size(); ++k) {
    const AppearanceClusterScore& c = scores.clusters[k];
    if (c.verdict == "true") scores.regions[static_cast<size_t>(c.region)].clusters.push_back(k);
    scores.true_clusters += c.verdict == "true" ? 1 : 0;
    scores.false_clusters += c.verdict == "false" ? 1 : 0;
    scores.explained_by_geometry += c.verdict == "explained_by_geometry" ? 1 : 0;
    scores.outside_region += c.verdict == "outside_region" ? 1 : 0;
  }
  for (size_t k = 0; k < truth.regions.size(); ++k) {
    AppearanceRegionScore& r = scores.regions[k];
    r.truth_points = tally[k].truth_points;
    r.measured_points = tally[k].measured_points;
    r.hit_points = tally[k].hit_points;
    r.status = truth.regions[k].geometric ? "geometric" : measuredStatus(tally[k], options);
    scores.detected += r.status == "detected" ? 1 : 0;
    scores.missed += r.status == "missed" ? 1 : 0;
    scores.not_measured += r.status == "not_measured" ? 1 : 0;
  }
  scores.recall_measured = ratio(scores.detected, scores.detected + scores.missed);
  scores.recall_all = ratio(scores.detected, scores.detected + scores.missed + scores.not_measured);
  scores.precision = ratio(scores.true_clusters, scores.true_clusters + scores.false_clusters);
  scores.stable = scoreStable(change, colour, flagged, on_albedo, on_shape, scores.clusters);
  return scores;
}

json appearanceScoresJson(const AppearanceScores& scores, const ChangeTruth& truth) {
  json regions = json::array();
  for (size_t k = 0; k < truth.regions.size(); ++k) {
    if (truth.regions[k].geometric) continue;
    regions.push_back(regionJson(truth.regions[k], scores.regions[k], scores.clusters));
  }
  json clusters = json::array();
  for (const AppearanceClusterScore& c : scores.clusters) {
    json j = change::appearanceClusterJson(c.cluster);
    const size_t n = c.cluster.core_points.size();
    j["verdict"] = c.verdict;
    j["region"] =
        c.region >= 0 ? json(truth.regions[static_cast<size_t>(c.region)].name) : json(nullptr);
    j["albedo_fraction"] = finiteOrNull(ratio(c.albedo_points, n));
    j["geometric_fraction"] = finiteOrNull(ratio(c.geometric_points, n));
    clusters.push_back(j);
  }
  return {{"status", "evaluated"},
          {"core_points_colour_measured", scores.colour_measured},
          {"regions_scored",
           {{"detected", scores.detected},
            {"missed", scores.missed},
            {"not_measured", scores.not_measured},
            {"recall_measured", finiteOrNull(scores.recall_measured)},
            {"recall_all", finiteOrNull(scores.recall_all)}}},
          {"clusters_scored",
           {{"true", scores.true_clusters},
            {"false", scores.false_clusters},
            {"explained_by_geometry", scores.explained_by_geometry},
            {"outside_region", scores.outside_region},
            {"precision", finiteOrNull(scores.precision)}}},
          {"stable", stableJson(scores.stable)},
          {"regions", regions},
          {"clusters", clusters}};
}

}  // namespace auv::recon::evaluate
