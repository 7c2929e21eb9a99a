// Regions of significant change: near points join, small ones are dropped, and a region counts
// as a change of interest only where min_change_m is reached over min_area_m2, not at one point.
#include "auv/recon/change/clusters.h"

#include <gtest/gtest.h>

namespace auv::recon::change {
namespace {

struct Patch {
  std::vector<Eigen::Vector3d> cores;
  std::vector<M3C2Point> comparison;

  /// Significant core points 0.2 m apart on a `side` x `side` square at x0, all `distance`.
  void add(double x0, int side, double distance) {
    for (int i = 0; i < side; ++i) {
      for (int j = 0; j < side; ++j) {
        cores.emplace_back(x0 + 0.2 * i, 0.2 * j, 10.0);
        M3C2Point p;
        p.distance = distance;
        p.significant = true;
        comparison.push_back(p);
      }
    }
  }
};

std::vector<ChangeCluster> clusters(const Patch& patch, double min_area_m2, double min_change_m) {
  return clusterChanges(patch.cores, patch.comparison, 0.2, 0.3, min_area_m2, min_change_m);
}

TEST(Clusters, NearPointsJoinAndSmallGroupsAreDropped) {
  Patch patch;
  patch.add(0.0, 5, 0.3);  // 1 m²
  patch.add(5.0, 1, 0.3);  // 0.04 m², alone
  const std::vector<ChangeCluster> found = clusters(patch, 0.05, 0.0);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_NEAR(found[0].area_m2, 1.0, 1e-9);
  EXPECT_NEAR(found[0].mean_distance_m, 0.3, 1e-9);
  EXPECT_NEAR(found[0].volume_gained_m3, 0.3, 1e-9);
  EXPECT_EQ(found[0].core_points.size(), 25u);
}

TEST(Clusters, OneSpikeOverTheSmallestChangeDoesNotMakeARegionOfInterest) {
  Patch spike;
  spike.add(0.0, 4, 0.05);  // 0.64 m² of 5 cm: significant, under the change of interest
  spike.comparison[5].distance = 0.25;  // one point of reconstruction noise over it
  EXPECT_TRUE(clusters(spike, 0.05, 0.1).empty());
  spike.comparison[6].distance = -0.12;  // a second one: 0.08 m² >= 0.05 m² changed >= 10 cm
  const std::vector<ChangeCluster> found = clusters(spike, 0.05, 0.1);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_NEAR(found[0].max_abs_distance_m, 0.25, 1e-9);
  // With no smallest change every significant group of the area is kept.
  spike.comparison[5].distance = spike.comparison[6].distance = 0.05;
  EXPECT_EQ(clusters(spike, 0.05, 0.0).size(), 1u);
  EXPECT_TRUE(clusters(spike, 0.05, 0.1).empty());
}

}  // namespace
}  // namespace auv::recon::change
