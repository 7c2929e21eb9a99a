#pragma once
// What the core points of a comparison reach of the change truth, shared by the scoring of the
// shape's change (change_scores.h) and of the colour's (appearance_scores.h): a core point
// measures the segment from survey 1's surface (the core point) to survey 2's (its far end; the
// core point alone where no distance was measured) and reaches the true changed points within
// match_radius_m of that segment. README.md, "Change against the truth".

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "auv/recon/evaluate/change_scores.h"
#include "auv/recon/evaluate/change_truth.h"

namespace auv::recon::evaluate {

/// Which true points the counted core points reach, and which region each core point reaches.
struct Reach {
  std::vector<char> truth_measured;  ///< per true point: reached by a counted core point
  std::vector<char> truth_hit;       ///< per true point: reached by a flagged one
  std::vector<int> core_region;      ///< per core point: region of the nearest reached point, -1
};

/// The core points counted (`counted`, and in the region of both visits) against the true points
/// of the regions `regions` selects (per region; empty = all), `flagged` the ones called changed.
Reach reachTruth(const ChangeTruth& truth, const WorldChange& change,
                 const std::vector<char>& counted, const std::vector<char>& flagged,
                 double radius_m, const std::vector<char>& regions = {});

/// Per true region: its points, those measured and those hit (from a Reach).
struct RegionTally {
  size_t truth_points = 0, measured_points = 0, hit_points = 0;
};
std::vector<RegionTally> tallyRegions(const ChangeTruth& truth, const Reach& reach);

/// detected, missed, or not_measured when less than min_measured_fraction of the region's
/// points were reached by a counted core point (the same rule for shape and colour).
std::string measuredStatus(const RegionTally& tally, const ChangeScoreOptions& options);

/// A cluster's core points against the regions they reach: how many reach one, and the region
/// most of them reach (-1: none).
struct ClusterReach {
  size_t hit_points = 0;
  int region = -1;
};
ClusterReach reachOfCluster(const std::vector<size_t>& core_points,
                            const std::vector<int>& core_region);

/// Most of a cluster's core points outside the region of both visits: not scored.
bool mostlyOutsideRegion(const WorldChange& change, const std::vector<size_t>& core_points);

/// Per core point: in a cluster that is scored (its verdict is not outside_region).
template <class ClusterScores>
std::vector<char> inScoredClusters(size_t core_points, const ClusterScores& clusters) {
  std::vector<char> in_cluster(core_points, 0);
  for (const auto& c : clusters) {
    if (c.verdict == "outside_region") continue;
    for (size_t i : c.cluster.core_points) in_cluster[i] = 1;
  }
  return in_cluster;
}

/// The `stable` core points (measured, in the region of both visits, reaching no truth), those
/// of them `flagged` and of those `in_cluster`, and their areas; the fraction is the caller's.
StableScore tallyStable(const WorldChange& change, const std::vector<char>& stable,
                        const std::vector<char>& flagged, const std::vector<char>& in_cluster);

/// part / whole; NaN when whole is 0.
double ratio(size_t part, size_t whole);

/// JSON has no NaN: such figures are written as null.
nlohmann::json finiteOrNull(double value);

/// At least min_hit_fraction of a cluster's `size` core points (and at least one).
bool enoughHits(size_t hits, size_t size, const ChangeScoreOptions& options);

}  // namespace auv::recon::evaluate
