#include "auv/recon/evaluate/change_reach.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "auv/recon/change/indexed_cloud.h"

namespace auv::recon::evaluate {
namespace {

double segmentDistance(const Eigen::Vector3d& q, const Eigen::Vector3d& a,
                       const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double length2 = ab.squaredNorm();
  const double t = length2 > 0 ? std::clamp((q - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
  return (q - (a + t * ab)).norm();
}

}  // namespace

Reach reachTruth(const ChangeTruth& truth, const WorldChange& change,
                 const std::vector<char>& counted, const std::vector<char>& flagged,
                 double radius_m, const std::vector<char>& regions) {
  Reach reach;
  reach.truth_measured.assign(truth.points.size(), 0);
  reach.truth_hit.assign(truth.points.size(), 0);
  reach.core_region.assign(change.points.size(), -1);
  if (truth.points.empty()) return reach;
  const change::IndexedCloud tree(truth.points);
  for (size_t i = 0; i < change.points.size(); ++i) {
    if (!change.inRegion(i) || !counted[i]) continue;
    // Not measured (a colour without a distance): the core point's own surface.
    const double d = change.measured(i) ? change.distances[i] : 0.0;
    const Eigen::Vector3d a = change.points[i];
    const Eigen::Vector3d b = a + d * change.normals[i];
    double nearest = std::numeric_limits<double>::infinity();
    for (int index : tree.within(0.5 * (a + b), radius_m + 0.5 * std::abs(d))) {
      const size_t j = static_cast<size_t>(index);
      const int region = truth.region_of_point[j];
      if (!regions.empty() && !regions[static_cast<size_t>(region)]) continue;
      const double distance = segmentDistance(truth.points[j], a, b);
      if (distance > radius_m) continue;
      reach.truth_measured[j] = 1;
      if (flagged[i]) reach.truth_hit[j] = 1;
      if (distance < nearest) {
        nearest = distance;
        reach.core_region[i] = region;
      }
    }
  }
  return reach;
}

std::vector<RegionTally> tallyRegions(const ChangeTruth& truth, const Reach& reach) {
  std::vector<RegionTally> tally(truth.regions.size());
  for (size_t j = 0; j < truth.points.size(); ++j) {
    RegionTally& r = tally[static_cast<size_t>(truth.region_of_point[j])];
    ++r.truth_points;
    r.measured_points += reach.truth_measured[j] ? 1 : 0;
    r.hit_points += reach.truth_hit[j] ? 1 : 0;
  }
  return tally;
}

std::string measuredStatus(const RegionTally& tally, const ChangeScoreOptions& options) {
  if (tally.truth_points == 0 ||
      static_cast<double>(tally.measured_points) <
          options.min_measured_fraction * static_cast<double>(tally.truth_points)) {
    return "not_measured";
  }
  return tally.hit_points > 0 &&
                 static_cast<double>(tally.hit_points) >=
                     options.min_hit_fraction * static_cast<double>(tally.measured_points)
             ? "detected"
             : "missed";
}

ClusterReach reachOfCluster(const std::vector<size_t>& core_points,
                            const std::vector<int>& core_region) {
  std::map<int, size_t> count;
  for (size_t i : core_points) {
    if (core_region[i] >= 0) ++count[core_region[i]];
  }
  ClusterReach reach;
  size_t most = 0;
  for (const auto& [region, n] : count) {
    reach.hit_points += n;
    if (n > most) {
      most = n;
      reach.region = region;
    }
  }
  return reach;
}

bool mostlyOutsideRegion(const WorldChange& change, const std::vector<size_t>& core_points) {
  size_t inside = 0;
  for (size_t i : core_points) inside += change.inRegion(i) ? 1 : 0;
  return 2 * inside < core_points.size();
}

StableScore tallyStable(const WorldChange& change, const std::vector<char>& stable,
                        const std::vector<char>& flagged, const std::vector<char>& in_cluster) {
  StableScore score;
  for (size_t i = 0; i < change.points.size(); ++i) {
    if (!stable[i]) continue;
    ++score.measured;
    if (!flagged[i]) continue;
    ++score.significant;
    score.significant_in_clusters += in_cluster[i] ? 1 : 0;
  }
  const double cell = change.core_spacing_m * change.core_spacing_m;
  score.area_m2 = static_cast<double>(score.significant) * cell;
  score.cluster_area_m2 = static_cast<double>(score.significant_in_clusters) * cell;
  return score;
}

double ratio(size_t part, size_t whole) {
  return whole == 0 ? std::numeric_limits<double>::quiet_NaN()
                    : static_cast<double>(part) / static_cast<double>(whole);
}

nlohmann::json finiteOrNull(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

bool enoughHits(size_t hits, size_t size, const ChangeScoreOptions& options) {
  return hits > 0 &&
         static_cast<double>(hits) >= options.min_hit_fraction * static_cast<double>(size);
}

}  // namespace auv::recon::evaluate
