#include "auv/recon/change/clusters.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <boost/math/distributions/normal.hpp>

#include "auv/recon/change/indexed_cloud.h"

namespace auv::recon::change {

nlohmann::json clusterJson(const ChangeCluster& c) {
  return {{"area_m2", c.area_m2},
          {"core_points", c.core_points.size()},
          {"mean_distance_m", c.mean_distance_m},
          {"max_abs_distance_m", c.max_abs_distance_m},
          {"volume_gained_m3", c.volume_gained_m3},
          {"volume_lost_m3", c.volume_lost_m3},
          {"centroid", {c.centroid.x(), c.centroid.y(), c.centroid.z()}},
          {"mean_level_of_detection_m", c.mean_level_of_detection_m},
          {"significance_z", c.significance_z}};
}

std::vector<std::vector<size_t>> linkFlagged(const std::vector<Eigen::Vector3d>& points,
                                             const std::vector<char>& flagged, double link_m) {
  std::vector<size_t> chosen;
  for (size_t i = 0; i < flagged.size(); ++i) {
    if (flagged[i]) chosen.push_back(i);
  }
  std::vector<std::vector<size_t>> groups;
  if (chosen.empty()) return groups;
  std::vector<Eigen::Vector3d> chosen_points;
  for (size_t i : chosen) chosen_points.push_back(points[i]);
  const IndexedCloud cloud(chosen_points);
  std::vector<bool> seen(chosen.size(), false);
  for (size_t seed = 0; seed < chosen.size(); ++seed) {
    if (seen[seed]) continue;
    std::vector<size_t> group;
    std::vector<size_t> queue{seed};
    seen[seed] = true;
    while (!queue.empty()) {
      const size_t k = queue.back();
      queue.pop_back();
      group.push_back(chosen[k]);
      for (int j : cloud.within(points[chosen[k]], link_m)) {
        if (!seen[static_cast<size_t>(j)]) {
          seen[static_cast<size_t>(j)] = true;
          queue.push_back(static_cast<size_t>(j));
        }
      }
    }
    std::sort(group.begin(), group.end());
    groups.push_back(std::move(group));
  }
  return groups;
}

namespace {

/// The clusters' volumes with the net change of their rim (clusterChanges' comment).
void addRimVolume(std::vector<ChangeCluster>& clusters,
                  const std::vector<Eigen::Vector3d>& core_points,
                  const std::vector<M3C2Point>& comparison, double cell_m2, double margin_m) {
  std::vector<int> claim(core_points.size(), -1);  // cluster of a point, or of its rim
  std::vector<double> nearest(core_points.size(), std::numeric_limits<double>::infinity());
  for (size_t c = 0; c < clusters.size(); ++c) {
    for (size_t index : clusters[c].core_points) nearest[index] = -1.0;  // its own
  }
  const IndexedCloud cloud(core_points);
  for (size_t c = 0; c < clusters.size(); ++c) {
    for (size_t index : clusters[c].core_points) {
      for (int j : cloud.within(core_points[index], margin_m)) {
        const size_t k = static_cast<size_t>(j);
        const double gap = (core_points[k] - core_points[index]).norm();
        if (!comparison[k].valid() || gap >= nearest[k]) continue;
        nearest[k] = gap;
        claim[k] = static_cast<int>(c);
      }
    }
  }
  std::vector<double> rim(clusters.size(), 0.0);
  for (size_t k = 0; k < claim.size(); ++k) {
    if (claim[k] >= 0) rim[static_cast<size_t>(claim[k])] += comparison[k].distance * cell_m2;
  }
  for (size_t c = 0; c < clusters.size(); ++c) {
    ChangeCluster& cluster = clusters[c];
    if (cluster.mean_distance_m > 0) {
      cluster.volume_gained_m3 = std::max(0.0, cluster.volume_gained_m3 + rim[c]);
    } else {
      cluster.volume_lost_m3 = std::max(0.0, cluster.volume_lost_m3 - rim[c]);
    }
  }
}

/// Mean, largest and volumes of `cluster`'s points from `comparison` (unmeasured points left
/// out); returns how many changed by at least `min_change_m`.
size_t measureCluster(ChangeCluster& cluster, const std::vector<M3C2Point>& comparison,
                      double cell_m2, double min_change_m) {
  cluster.mean_distance_m = cluster.max_abs_distance_m = 0.0;
  cluster.volume_gained_m3 = cluster.volume_lost_m3 = 0.0;
  cluster.mean_level_of_detection_m = 0.0;
  size_t of_interest = 0, measured = 0;
  for (size_t index : cluster.core_points) {
    if (!comparison[index].valid()) continue;
    const double d = comparison[index].distance;
    ++measured;
    of_interest += std::abs(d) >= min_change_m ? 1 : 0;
    cluster.mean_distance_m += d;
    cluster.mean_level_of_detection_m += comparison[index].level_of_detection;
    if (std::abs(d) > std::abs(cluster.max_abs_distance_m)) cluster.max_abs_distance_m = d;
    (d > 0 ? cluster.volume_gained_m3 : cluster.volume_lost_m3) += std::abs(d) * cell_m2;
  }
  if (measured > 0) {
    cluster.mean_distance_m /= static_cast<double>(measured);
    cluster.mean_level_of_detection_m /= static_cast<double>(measured);
  }
  return of_interest;
}

/// RegionOptions::grow_at_measuring_scale: each region, largest first, takes breadth first the
/// core points within link_m of it that `measurement` finds significant with the region's sign
/// and no region holds yet.
void growRegions(std::vector<ChangeCluster>& regions,
                 const std::vector<Eigen::Vector3d>& core_points,
                 const std::vector<M3C2Point>& measurement, double link_m, double cell_m2) {
  std::vector<char> taken(core_points.size(), 0);
  for (const ChangeCluster& region : regions) {
    for (size_t index : region.core_points) taken[index] = 1;
  }
  const IndexedCloud cloud(core_points);
  for (ChangeCluster& region : regions) {
    const bool gained = region.mean_distance_m > 0;
    std::vector<size_t> queue = region.core_points;
    while (!queue.empty()) {
      const size_t k = queue.back();
      queue.pop_back();
      for (int j : cloud.within(core_points[k], link_m)) {
        const size_t next = static_cast<size_t>(j);
        const M3C2Point& p = measurement[next];
        if (taken[next] || !p.valid() || !p.significant || (p.distance > 0) != gained) continue;
        taken[next] = 1;
        region.core_points.push_back(next);
        queue.push_back(next);
      }
    }
    std::sort(region.core_points.begin(), region.core_points.end());
    region.area_m2 = static_cast<double>(region.core_points.size()) * cell_m2;
    region.centroid.setZero();
    for (size_t index : region.core_points) region.centroid += core_points[index];
    region.centroid /= static_cast<double>(region.core_points.size());
  }
  std::sort(regions.begin(), regions.end(),
            [](const ChangeCluster& a, const ChangeCluster& b) { return a.area_m2 > b.area_m2; });
}

}  // namespace

void remeasureClusters(std::vector<ChangeCluster>& clusters,
                       const std::vector<Eigen::Vector3d>& core_points,
                       const std::vector<M3C2Point>& measurement, double spacing_m,
                       double volume_margin_m) {
  const double cell = spacing_m * spacing_m;
  for (ChangeCluster& cluster : clusters) measureCluster(cluster, measurement, cell, 0.0);
  if (volume_margin_m > 0 && !clusters.empty())
    addRimVolume(clusters, core_points, measurement, cell, volume_margin_m);
}

double familyWiseZ(const RegionOptions& options, size_t measured_points) {
  if (options.family_confidence <= 0 || options.footprint_m2 <= 0) return 0.0;
  const double site_m2 =
      static_cast<double>(measured_points) * options.spacing_m * options.spacing_m;
  const double independent = std::max(1.0, site_m2 / options.footprint_m2);
  const double p = 1.0 - (1.0 - options.family_confidence) / (2.0 * independent);
  return boost::math::quantile(boost::math::normal(), p);
}

std::vector<ChangeCluster> clusterChanges(const std::vector<Eigen::Vector3d>& core_points,
                                          const std::vector<M3C2Point>& comparison,
                                          double spacing_m, double link_m, double min_area_m2,
                                          double min_change_m, double volume_margin_m) {
  std::vector<char> significant(comparison.size());
  for (size_t i = 0; i < comparison.size(); ++i) significant[i] = comparison[i].significant;
  const double cell = spacing_m * spacing_m;
  std::vector<ChangeCluster> clusters;
  for (std::vector<size_t>& group : linkFlagged(core_points, significant, link_m)) {
    ChangeCluster cluster;
    const double n = static_cast<double>(group.size());
    cluster.area_m2 = n * cell;
    if (cluster.area_m2 < min_area_m2) continue;
    cluster.core_points = std::move(group);
    // A change of interest has min_change_m over min_area_m2, not at one point: a lone spike of
    // reconstruction noise on a patch that moved a few centimetres is not one.
    const size_t of_interest = measureCluster(cluster, comparison, cell, min_change_m);
    if (of_interest == 0 || static_cast<double>(of_interest) * cell < min_area_m2) continue;
    for (size_t index : cluster.core_points) cluster.centroid += core_points[index];
    cluster.centroid /= n;
    clusters.push_back(std::move(cluster));
  }
  if (volume_margin_m > 0 && !clusters.empty()) {
    addRimVolume(clusters, core_points, comparison, cell, volume_margin_m);
  }
  std::sort(clusters.begin(), clusters.end(),
            [](const ChangeCluster& a, const ChangeCluster& b) { return a.area_m2 > b.area_m2; });
  return clusters;
}

std::vector<ChangeCluster> findRegions(const std::vector<Eigen::Vector3d>& core_points,
                                       const std::vector<M3C2Point>& detection,
                                       const std::vector<M3C2Point>* measurement,
                                       const RegionOptions& options) {
  std::vector<ChangeCluster> regions =
      clusterChanges(core_points, detection, options.spacing_m, options.link_m, options.min_area_m2,
                     options.min_change_m, 0.0);
  const std::vector<M3C2Point>& measuring = measurement ? *measurement : detection;
  if (measurement && options.grow_at_measuring_scale) {
    growRegions(regions, core_points, measuring, options.link_m,
                options.spacing_m * options.spacing_m);
  }
  remeasureClusters(regions, core_points, measuring, options.spacing_m, 0.0);
  const size_t measured = static_cast<size_t>(std::count_if(
      measuring.begin(), measuring.end(), [](const M3C2Point& p) { return p.valid(); }));
  for (ChangeCluster& r : regions) {
    if (r.mean_level_of_detection_m > 0) {
      r.significance_z =
          options.level_of_detection_z * std::abs(r.mean_distance_m) / r.mean_level_of_detection_m;
    }
  }
  const double z = familyWiseZ(options, measured);
  regions.erase(std::remove_if(regions.begin(), regions.end(),
                               [z](const ChangeCluster& r) { return r.significance_z < z; }),
                regions.end());
  if (options.volume_margin_m > 0 && !regions.empty()) {
    addRimVolume(regions, core_points, measuring, options.spacing_m * options.spacing_m,
                 options.volume_margin_m);
  }
  return regions;
}

}  // namespace auv::recon::change
