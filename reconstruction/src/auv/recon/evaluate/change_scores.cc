#include "auv/recon/evaluate/change_scores.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include <open3d/geometry/KDTreeFlann.h>

#include "auv/recon/common/stage_error.h"

using nlohmann::json;

namespace auv::recon::evaluate {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// JSON has no NaN: such figures are written as null.
json number(double value) { return std::isfinite(value) ? json(value) : json(nullptr); }

double ratio(size_t part, size_t whole) {
  return whole == 0 ? kNaN : static_cast<double>(part) / static_cast<double>(whole);
}

double segmentDistance(const Eigen::Vector3d& q, const Eigen::Vector3d& a,
                       const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double length2 = ab.squaredNorm();
  const double t = length2 > 0 ? std::clamp((q - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
  return (q - (a + t * ab)).norm();
}

/// Which true points the measured core points reach, and which region each reaches first.
struct Reach {
  std::vector<char> truth_measured, truth_hit;  ///< per true point
  std::vector<int> core_region;  ///< per measured core point: the nearest region it reaches, -1
};

Reach reachTruth(const ChangeTruth& truth, const WorldChange& change, double radius_m) {
  Reach reach;
  reach.truth_measured.assign(truth.points.size(), 0);
  reach.truth_hit.assign(truth.points.size(), 0);
  reach.core_region.assign(change.points.size(), -1);
  if (truth.points.empty()) return reach;
  Eigen::MatrixXd matrix(3, static_cast<Eigen::Index>(truth.points.size()));
  for (size_t j = 0; j < truth.points.size(); ++j) {
    matrix.col(static_cast<Eigen::Index>(j)) = truth.points[j];
  }
  const open3d::geometry::KDTreeFlann tree(matrix);  // refers to `matrix`: kept alive here
  std::vector<int> near;
  std::vector<double> distance2;
  for (size_t i = 0; i < change.points.size(); ++i) {
    if (!change.inRegion(i) || !change.measured(i)) continue;
    const Eigen::Vector3d a = change.points[i];
    const Eigen::Vector3d b = a + change.distances[i] * change.normals[i];
    tree.SearchRadius(Eigen::Vector3d(0.5 * (a + b)),
                      radius_m + 0.5 * std::abs(change.distances[i]), near, distance2);
    double nearest = std::numeric_limits<double>::infinity();
    for (int index : near) {
      const size_t j = static_cast<size_t>(index);
      const double d = segmentDistance(truth.points[j], a, b);
      if (d > radius_m) continue;
      reach.truth_measured[j] = 1;
      if (change.significant[i]) reach.truth_hit[j] = 1;
      if (d < nearest) {
        nearest = d;
        reach.core_region[i] = truth.region_of_point[j];
      }
    }
  }
  return reach;
}

std::string regionStatus(const TrueChangeRegion& region, const RegionScore& score,
                         const ChangeScoreOptions& options) {
  if (!region.geometric) return "appearance";
  if (region.magnitude() < options.min_magnitude_m) return "below_min_magnitude";
  if (score.truth_points == 0 ||
      static_cast<double>(score.measured_points) <
          options.min_measured_fraction * static_cast<double>(score.truth_points)) {
    return "not_measured";
  }
  return score.hit_points > 0 &&
                 static_cast<double>(score.hit_points) >=
                     options.min_hit_fraction * static_cast<double>(score.measured_points)
             ? "detected"
             : "missed";
}

/// Each cluster: on which region, if any, and whether it counts as true, false or neither.
std::vector<ClusterScore> scoreClusters(const ChangeTruth& truth, const WorldChange& change,
                                        const Reach& reach, const ChangeScoreOptions& options) {
  std::vector<change::M3C2Point> comparison(change.points.size());
  for (size_t i = 0; i < comparison.size(); ++i) {
    comparison[i].normal = change.normals[i];
    comparison[i].distance = change.distances[i];
    comparison[i].significant = change.significant[i] && change.measured(i);
  }
  const double min_area =
      options.min_cluster_area_m2 > 0 ? options.min_cluster_area_m2 : change.min_cluster_area_m2;
  // Joined as compare joins them (clusters.h): within 1.5 core spacings.
  const std::vector<change::ChangeCluster> clusters =
      change::clusterChanges(change.points, comparison, change.core_spacing_m,
                             1.5 * change.core_spacing_m, min_area, change.min_change_m);
  std::vector<ClusterScore> scores;
  for (const change::ChangeCluster& cluster : clusters) {
    ClusterScore score;
    score.cluster = cluster;
    size_t inside = 0;
    std::map<int, size_t> tally;
    for (size_t i : cluster.core_points) {
      inside += change.inRegion(i) ? 1 : 0;
      if (reach.core_region[i] >= 0) ++tally[reach.core_region[i]];
    }
    size_t most = 0;
    for (const auto& [region, count] : tally) {
      score.hit_points += count;
      if (count > most) {
        most = count;
        score.region = region;
      }
    }
    const double n = static_cast<double>(cluster.core_points.size());
    if (2 * inside < cluster.core_points.size()) {
      score.verdict = "outside_region";
    } else if (score.hit_points > 0 &&
               static_cast<double>(score.hit_points) >= options.min_hit_fraction * n) {
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
  std::vector<char> in_cluster(change.points.size(), 0);
  for (const ClusterScore& c : clusters) {
    if (c.verdict == "outside_region") continue;
    for (size_t i : c.cluster.core_points) in_cluster[i] = 1;
  }
  StableScore stable;
  for (size_t i = 0; i < change.points.size(); ++i) {
    if (!change.inRegion(i) || !change.measured(i) || reach.core_region[i] >= 0) continue;
    ++stable.measured;
    if (!change.significant[i]) continue;
    ++stable.significant;
    stable.significant_in_clusters += in_cluster[i] ? 1 : 0;
  }
  const double cell = change.core_spacing_m * change.core_spacing_m;
  stable.fraction = ratio(stable.significant, stable.measured);
  stable.area_m2 = static_cast<double>(stable.significant) * cell;
  stable.cluster_area_m2 = static_cast<double>(stable.significant_in_clusters) * cell;
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
            {"measured_fraction", number(ratio(score.measured_points, score.truth_points))},
            {"hit_fraction", number(ratio(score.hit_points, score.measured_points))},
            {"clusters", score.clusters}};
  if (score.clusters.empty()) return j;
  const change::ChangeCluster& m = score.measured;
  // The side of the change the truth has most of: a block's gained or lost volume.
  const bool gained = truth.volume_gained_m3 >= truth.volume_lost_m3;
  const double true_volume = gained ? truth.volume_gained_m3 : truth.volume_lost_m3;
  const double volume = gained ? m.volume_gained_m3 : m.volume_lost_m3;
  j["measured"] = change::clusterJson(m);
  j["measured"].erase("core_points");
  j["errors"] = {
      {"mean_distance_m", m.mean_distance_m - truth.mean_distance_m},
      {"max_distance_m", m.max_abs_distance_m - truth.max_distance_m},
      {"volume_side", gained ? "gained" : "lost"},
      {"volume_true_m3", true_volume},
      {"volume_measured_m3", volume},
      {"volume_relative", number(relativeError(volume, true_volume))},
      {"volume_gained_relative", number(relativeError(m.volume_gained_m3, truth.volume_gained_m3))},
      {"volume_lost_relative", number(relativeError(m.volume_lost_m3, truth.volume_lost_m3))}};
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
  const Reach reach = reachTruth(truth, change, options.match_radius_m);
  ChangeScores scores;
  scores.regions.resize(truth.regions.size());
  for (size_t j = 0; j < truth.points.size(); ++j) {
    RegionScore& r = scores.regions[static_cast<size_t>(truth.region_of_point[j])];
    ++r.truth_points;
    r.measured_points += reach.truth_measured[j] ? 1 : 0;
    r.hit_points += reach.truth_hit[j] ? 1 : 0;
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
    r.status = regionStatus(truth.regions[k], r, options);
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
    j["hit_fraction"] = number(ratio(c.hit_points, c.cluster.core_points.size()));
    clusters.push_back(j);
  }
  const StableScore& s = scores.stable;
  return {{"regions_scored",
           {{"detected", scores.detected},
            {"missed", scores.missed},
            {"not_measured", scores.not_measured},
            {"recall_measured", number(scores.recall_measured)},
            {"recall_all", number(scores.recall_all)}}},
          {"clusters_scored",
           {{"true", scores.true_clusters},
            {"false", scores.false_clusters},
            {"precision", number(scores.precision)}}},
          {"stable",
           {{"core_points_measured", s.measured},
            {"core_points_significant", s.significant},
            {"core_points_significant_in_clusters", s.significant_in_clusters},
            {"false_fraction", number(s.fraction)},
            {"false_area_m2", s.area_m2},
            {"false_cluster_area_m2", s.cluster_area_m2}}},
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
