// Regions of significant change: near points join, small ones are dropped, and a region counts
// as a change of interest only where min_change_m is reached over min_area_m2, not at one point;
// a region's volume takes the rim M3C2 blurred it into.
#include "auv/recon/change/clusters.h"

#include <gtest/gtest.h>

#include <limits>

namespace auv::recon::change {
namespace {

struct Patch {
  std::vector<Eigen::Vector3d> cores;
  std::vector<M3C2Point> comparison;

  /// Core points 0.2 m apart on a `side` x `side` square at (x0, y0), all `distance`.
  void add(double x0, int side, double distance, bool significant = true, double y0 = 0.0,
           double level_of_detection = 0.1) {
    for (int i = 0; i < side; ++i) {
      for (int j = 0; j < side; ++j) {
        cores.emplace_back(x0 + 0.2 * i, y0 + 0.2 * j, 10.0);
        M3C2Point p;
        p.distance = distance;
        p.level_of_detection = level_of_detection;
        p.significant = significant;
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

TEST(Clusters, TheVolumeTakesTheBlurredRimAndNotTheNoiseAroundIt) {
  // A 1 m² block of +0.3 m whose change M3C2 spread, below the level of detection, over a rim
  // one core spacing wide (+0.1 m), amid unchanged ground whose noise is ±2 cm.
  Patch site;
  site.add(-1.0, 15, 0.0, false, -1.0);  // 3 x 3 m of measured ground, none significant
  for (size_t i = 0; i < site.cores.size(); ++i) {
    const Eigen::Vector3d& c = site.cores[i];
    const bool in_rim = c.x() > -0.25 && c.x() < 1.05 && c.y() > -0.25 && c.y() < 1.05;
    site.comparison[i].distance = in_rim ? 0.1 : ((i % 2) ? 0.02 : -0.02);
  }
  for (size_t i = 0; i < site.cores.size(); ++i) {
    const Eigen::Vector3d& c = site.cores[i];
    if (c.x() > -0.05 && c.x() < 0.85 && c.y() > -0.05 && c.y() < 0.85) {
      site.comparison[i].distance = 0.3;  // the block: 5 x 5 points
      site.comparison[i].significant = true;
    }
  }
  const auto without = clusterChanges(site.cores, site.comparison, 0.2, 0.3, 0.05, 0.1);
  ASSERT_EQ(without.size(), 1u);
  EXPECT_NEAR(without[0].volume_gained_m3, 25 * 0.3 * 0.04, 1e-9);
  const auto with = clusterChanges(site.cores, site.comparison, 0.2, 0.3, 0.05, 0.1, 0.3);
  ASSERT_EQ(with.size(), 1u);
  // + the rim: 7 x 7 - 5 x 5 = 24 points of 0.1 m; the noise beyond 0.3 m is not taken.
  EXPECT_NEAR(with[0].volume_gained_m3, (25 * 0.3 + 24 * 0.1) * 0.04, 1e-9);
  EXPECT_EQ(with[0].volume_lost_m3, 0.0);
  EXPECT_EQ(with[0].core_points.size(), 25u) << "the rim adds volume, not area";
  // A wider margin takes noise that cancels: 9 x 9 - 7 x 7 = 32 points of ±2 cm.
  const auto wide = clusterChanges(site.cores, site.comparison, 0.2, 0.3, 0.05, 0.1, 0.45);
  EXPECT_NEAR(wide[0].volume_gained_m3, with[0].volume_gained_m3, 0.02 * 0.04 * 5);
}

TEST(Clusters, AtTwoScalesTheCoarseFindsTheRegionAndTheFineMeasuresIt) {
  // The coarse comparison (a wider cylinder) sees a 1 m² block spread over 1.44 m² at +0.2 m;
  // the fine one measures the block at +0.3 m and its surroundings at 0, one point unmeasured.
  Patch coarse, fine;
  coarse.add(-0.2, 6, 0.2);
  fine.add(-0.2, 6, 0.0, false);
  for (size_t i = 0; i < fine.cores.size(); ++i) {
    const Eigen::Vector3d& c = fine.cores[i];
    if (c.x() > -0.05 && c.y() > 0.15) fine.comparison[i].distance = 0.3;  // 5 x 5 points
  }
  fine.comparison[0].distance = std::numeric_limits<double>::quiet_NaN();  // not measured
  ASSERT_FALSE(fine.comparison[0].valid());
  std::vector<ChangeCluster> found =
      clusterChanges(coarse.cores, coarse.comparison, 0.2, 0.3, 0.05, 0.1);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_NEAR(found[0].volume_gained_m3, 36 * 0.2 * 0.04, 1e-9);
  remeasureClusters(found, fine.cores, fine.comparison, 0.2, 0.0);
  EXPECT_EQ(found[0].core_points.size(), 36u);  // the region is the coarse one
  EXPECT_NEAR(found[0].area_m2, 36 * 0.04, 1e-9);
  EXPECT_NEAR(found[0].volume_gained_m3, 25 * 0.3 * 0.04, 1e-9);  // its volume the fine one
  EXPECT_NEAR(found[0].mean_distance_m, 25 * 0.3 / 35, 1e-9);     // over the measured 35
  EXPECT_NEAR(found[0].max_abs_distance_m, 0.3, 1e-9);
}

TEST(Regions, FamilyWiseBoundGrowsWithTheSitesIndependentMeasurements) {
  RegionOptions options;
  options.spacing_m = 0.2;
  options.footprint_m2 = 0.04;  // one core point per independent measurement
  EXPECT_EQ(familyWiseZ(options, 1000), 0.0) << "off without a confidence";
  options.family_confidence = 0.95;
  EXPECT_NEAR(familyWiseZ(options, 1), 1.959964, 1e-5);     // one measurement: M3C2's own 95 %
  EXPECT_NEAR(familyWiseZ(options, 0), 1.959964, 1e-5);     // never fewer than one
  EXPECT_NEAR(familyWiseZ(options, 1000), 4.055626, 1e-5);  // Φ⁻¹(1 − 0.05 / 2000)
  options.footprint_m2 = 0.4;                               // ten core points each
  EXPECT_NEAR(familyWiseZ(options, 1000), 3.480756, 1e-5);  // Φ⁻¹(1 − 0.05 / 200)
}

TEST(Regions, OnlyChangesSignificantOverTheWholeSiteAreKept) {
  // 1 600 measured core points of unchanged ground (LoD 0.1 m), a block 0.5 m high
  // (z = 1.96 x 5) and a patch where the reconstructions disagree by 0.15 m (z = 2.9): each
  // point of the patch passes its 95 % level of detection, the patch as a region does not pass
  // the bound over the site's 1 600 measurements (z 4.2).
  Patch site;
  site.add(0.0, 40, 0.0, false, -10.0);
  site.add(0.0, 5, 0.5);
  site.add(4.0, 4, 0.15);
  RegionOptions options;
  options.min_change_m = 0.1;
  options.footprint_m2 = 0.04;
  const std::vector<ChangeCluster> all = findRegions(site.cores, site.comparison, nullptr, options);
  ASSERT_EQ(all.size(), 2u) << "without the family-wise test both are regions";
  EXPECT_NEAR(all[0].significance_z, 1.96 * 5, 1e-9);
  EXPECT_NEAR(all[1].significance_z, 1.96 * 1.5, 1e-9);
  EXPECT_NEAR(all[1].mean_level_of_detection_m, 0.1, 1e-9);

  options.family_confidence = 0.95;
  const std::vector<ChangeCluster> kept =
      findRegions(site.cores, site.comparison, nullptr, options);
  ASSERT_EQ(kept.size(), 1u);
  EXPECT_NEAR(kept[0].mean_distance_m, 0.5, 1e-9);
  EXPECT_NEAR(kept[0].area_m2, 1.0, 1e-9);

  // A site of four independent measurements (41 core points, a cylinder over ten) has few
  // chances of a false region: the same patch then stands (bound z 2.5).
  Patch small;
  small.add(0.0, 5, 0.5);
  small.add(4.0, 4, 0.15);
  options.footprint_m2 = 0.4;
  EXPECT_EQ(findRegions(small.cores, small.comparison, nullptr, options).size(), 2u)
      << "bound z " << familyWiseZ(options, 41);
}

TEST(Regions, ARegionGrowsAtTheMeasuringScaleToTheEdgesItsCoarseScaleBlurred) {
  // A block of 4 x 4 core points (0.64 m², +0.4 m) on 12 x 12 of unchanged ground: the coarse
  // cylinders average its edges with the floor, so only its middle 2 x 2 pass there; the fine
  // ones see all of it. Beside it a hole (significant at the fine scale, lost), and apart a
  // fine-significant patch that no coarse region seeds.
  std::vector<Eigen::Vector3d> cores;
  std::vector<M3C2Point> coarse, fine;
  for (int i = 0; i < 12; ++i) {
    for (int j = 0; j < 12; ++j) {
      cores.emplace_back(0.2 * i, 0.2 * j, 10.0);
      const bool block = i >= 4 && i < 8 && j >= 4 && j < 8;
      const bool middle = i >= 5 && i < 7 && j >= 5 && j < 7;
      const bool hole = i == 8 && j == 5;
      const bool apart = i >= 10 && j < 2;
      M3C2Point c, f;
      c.distance = middle ? 0.3 : block ? 0.1 : 0.0;
      c.level_of_detection = 0.1;
      c.significant = middle;
      f.distance = block ? 0.4 : hole ? -0.3 : apart ? 0.3 : 0.0;
      f.level_of_detection = 0.05;
      f.significant = block || hole || apart;
      coarse.push_back(c);
      fine.push_back(f);
    }
  }
  RegionOptions options;
  const std::vector<ChangeCluster> seeds = findRegions(cores, coarse, &fine, options);
  ASSERT_EQ(seeds.size(), 1u);
  EXPECT_EQ(seeds[0].core_points.size(), 4u);
  EXPECT_NEAR(seeds[0].volume_gained_m3, 4 * 0.4 * 0.04, 1e-9);

  options.grow_at_measuring_scale = true;
  const std::vector<ChangeCluster> grown = findRegions(cores, coarse, &fine, options);
  ASSERT_EQ(grown.size(), 1u) << "the apart patch has no coarse seed";
  EXPECT_EQ(grown[0].core_points.size(), 16u) << "the hole beside it has the other sign";
  EXPECT_NEAR(grown[0].area_m2, 0.64, 1e-9);
  EXPECT_NEAR(grown[0].volume_gained_m3, 16 * 0.4 * 0.04, 1e-9);
  EXPECT_NEAR(grown[0].volume_lost_m3, 0.0, 1e-9);
  EXPECT_TRUE(grown[0].centroid.isApprox(Eigen::Vector3d(1.1, 1.1, 10.0), 1e-9));

  // One scale: nothing to grow into (the measuring scale is the detection scale).
  EXPECT_EQ(findRegions(cores, coarse, nullptr, options)[0].core_points.size(), 4u);
}

}  // namespace
}  // namespace auv::recon::change
