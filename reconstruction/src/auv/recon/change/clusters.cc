#include "auv/recon/change/clusters.h"

#include <algorithm>
#include <cmath>

#include <open3d/geometry/KDTreeFlann.h>

namespace auv::recon::change {

std::vector<ChangeCluster> clusterChanges(const std::vector<Eigen::Vector3d>& core_points,
                                          const std::vector<M3C2Point>& comparison,
                                          double spacing_m, double link_m, double min_area_m2) {
  std::vector<size_t> significant;
  for (size_t i = 0; i < comparison.size(); ++i) {
    if (comparison[i].significant) significant.push_back(i);
  }
  std::vector<ChangeCluster> clusters;
  if (significant.empty()) return clusters;
  Eigen::MatrixXd matrix(3, static_cast<Eigen::Index>(significant.size()));
  for (size_t k = 0; k < significant.size(); ++k) {
    matrix.col(static_cast<Eigen::Index>(k)) = core_points[significant[k]];
  }
  const open3d::geometry::KDTreeFlann tree(matrix);  // refers to `matrix`: kept alive here
  const double cell = spacing_m * spacing_m;
  std::vector<bool> seen(significant.size(), false);
  std::vector<int> near;
  std::vector<double> distance2;
  for (size_t seed = 0; seed < significant.size(); ++seed) {
    if (seen[seed]) continue;
    ChangeCluster cluster;
    std::vector<size_t> queue{seed};
    seen[seed] = true;
    while (!queue.empty()) {
      const size_t k = queue.back();
      queue.pop_back();
      const size_t index = significant[k];
      cluster.core_points.push_back(index);
      const double d = comparison[index].distance;
      cluster.mean_distance_m += d;
      if (std::abs(d) > std::abs(cluster.max_abs_distance_m)) cluster.max_abs_distance_m = d;
      (d > 0 ? cluster.volume_gained_m3 : cluster.volume_lost_m3) += std::abs(d) * cell;
      cluster.centroid += core_points[index];
      tree.SearchRadius(Eigen::Vector3d(core_points[index]), link_m, near, distance2);
      for (int j : near) {
        if (!seen[static_cast<size_t>(j)]) {
          seen[static_cast<size_t>(j)] = true;
          queue.push_back(static_cast<size_t>(j));
        }
      }
    }
    const double n = static_cast<double>(cluster.core_points.size());
    cluster.area_m2 = n * cell;
    if (cluster.area_m2 < min_area_m2) continue;
    cluster.mean_distance_m /= n;
    cluster.centroid /= n;
    std::sort(cluster.core_points.begin(), cluster.core_points.end());
    clusters.push_back(std::move(cluster));
  }
  std::sort(clusters.begin(), clusters.end(),
            [](const ChangeCluster& a, const ChangeCluster& b) { return a.area_m2 > b.area_m2; });
  return clusters;
}

}  // namespace auv::recon::change
