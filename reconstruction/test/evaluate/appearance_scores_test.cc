// The colour change found by `auv recon compare` scored against the simulator's change truth
// (appearance_scores.h): known answers on a synthetic seabed — an albedo patch detected, a
// faint one missed, one off the grid not measured, a recoloured patch of stable seabed counted
// false, and the colour change at the foot of a fallen block explained by geometry, not false.
#include <gtest/gtest.h>

#include <limits>

#include "auv/recon/evaluate/appearance_scores.h"
#include "auv/recon/evaluate/change_scores.h"
#include "auv/recon/evaluate/change_truth.h"
#include "change_files.h"
#include "synthetic_scene.h"

namespace auv::recon::evaluate {
namespace {

using nlohmann::json;
using testing::boxRegion;
using testing::rectangleRegion;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

bool inside(const Eigen::Vector3d& p, double x0, double x1, double y0, double y1) {
  return p.x() > x0 && p.x() < x1 && p.y() > y0 && p.y() < y1;
}

/// A seabed at depth 5 (NED) with a 2 x 2 x 1 m block fallen on it and three albedo patches;
/// compare's core points every 0.2 m (x, y = -9.9 ... 9.9), ΔE 2 on the unchanged seabed.
class AppearanceScoresTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto folder = testing::freshFolder("appearance_scores");
    testing::writeChangeTruthFiles(
        folder, {boxRegion("block", "add", -6, -4, -6, -4, 4.0, 5.0),
                 rectangleRegion("bleach", "albedo", -6, -4, 4, 6, 5.0, 0.0),
                 rectangleRegion("faint", "albedo", 4, 6, 4, 6, 5.0, 0.0),  // below threshold
                 rectangleRegion("far_bleach", "albedo", 15, 16, 15, 16, 5.0, 0.0)});
    truth_ = readChangeTruth(folder / "changes.json");
    for (int i = 0; i < 100; ++i) {
      for (int j = 0; j < 100; ++j) {
        const Eigen::Vector3d p(-9.9 + 0.2 * i, -9.9 + 0.2 * j, 5.0);
        change_.points.push_back(p);
        change_.normals.emplace_back(0, 0, -1);
        const bool on_block = inside(p, -6, -4, -6, -4);
        // The shape's change: the block. compare leaves its colour uncompared.
        change_.distances.push_back(p.x() > 9.0 ? kNaN : on_block ? 1.0 : 0.0);
        change_.significant.push_back(on_block);
        double delta_e = 2.0;
        bool significant = false;
        if (on_block || p.x() > 9.0) delta_e = kNaN;
        // The block's colour at its foot: the core points just outside it (within 0.3 m of its
        // sides' truth), whose shape did not change significantly.
        const bool foot = inside(p, -6.3, -3.7, -6.3, -3.7) && !on_block;
        if (inside(p, -6, -4, 4, 6) || foot) delta_e = 20, significant = true;
        if (inside(p, 4, 6, 4, 6)) delta_e = 6;                         // seen, not significant
        if (inside(p, 1, 2, -2, -1)) delta_e = 15, significant = true;  // false: 25 points
        if (inside(p, 8.0, 8.2, 0.0, 0.2)) delta_e = 15, significant = true;  // one false point
        change_.delta_e.push_back(delta_e);
        change_.appearance_significant.push_back(significant);
      }
    }
    change_.core_spacing_m = 0.2;
    change_.min_cluster_area_m2 = 0.05;
  }

  const AppearanceRegionScore& region(const AppearanceScores& s, const std::string& name) const {
    for (size_t k = 0; k < truth_.regions.size(); ++k) {
      if (truth_.regions[k].name == name) return s.regions[k];
    }
    throw std::runtime_error("no region " + name);
  }

  /// The cluster whose centroid lies in the rectangle.
  const AppearanceClusterScore& clusterAt(const AppearanceScores& s, double x0, double x1,
                                          double y0, double y1) const {
    for (const AppearanceClusterScore& c : s.clusters) {
      if (inside(c.cluster.centroid, x0, x1, y0, y1)) return c;
    }
    throw std::runtime_error("no cluster there");
  }

  ChangeTruth truth_;
  WorldChange change_;
};

TEST_F(AppearanceScoresTest, AlbedoPatchDetectedFaintOneMissed) {
  const AppearanceScores s = scoreAppearance(truth_, change_, ChangeScoreOptions());
  EXPECT_EQ(region(s, "bleach").status, "detected");
  EXPECT_EQ(region(s, "faint").status, "missed");
  EXPECT_EQ(region(s, "far_bleach").status, "not_measured");
  EXPECT_EQ(region(s, "block").status, "geometric");
  EXPECT_EQ(s.detected, 1u);
  EXPECT_EQ(s.missed, 1u);
  EXPECT_EQ(s.not_measured, 1u);
  EXPECT_DOUBLE_EQ(s.recall_measured, 1.0 / 2.0);
  EXPECT_DOUBLE_EQ(s.recall_all, 1.0 / 3.0);
  // Every measured point of the patch is hit: its 10 x 10 core points, 4 m².
  EXPECT_EQ(region(s, "bleach").hit_points, region(s, "bleach").measured_points);
  const AppearanceClusterScore& bleach = clusterAt(s, -6, -4, 4, 6);
  EXPECT_EQ(bleach.verdict, "true");
  EXPECT_EQ(truth_.regions[static_cast<size_t>(bleach.region)].name, "bleach");
  EXPECT_NEAR(bleach.cluster.area_m2, 4.0, 1e-9);
  EXPECT_NEAR(bleach.cluster.mean_delta_e, 20.0, 1e-9);
  ASSERT_EQ(region(s, "bleach").clusters.size(), 1u);

  const json j = appearanceScoresJson(s, truth_);
  EXPECT_EQ(j["status"], "evaluated");
  ASSERT_EQ(j["regions"].size(), 3u);  // the albedo regions only
  EXPECT_EQ(j["regions"][0]["name"], "bleach");
  EXPECT_EQ(j["regions"][0]["status"], "detected");
  EXPECT_NEAR(j["regions"][0]["measured"]["area_m2"].get<double>(), 4.0, 1e-9);
  EXPECT_NEAR(j["regions"][0]["measured"]["area_relative"].get<double>(), 0.0, 1e-9);
  EXPECT_FALSE(j["regions"][1].contains("measured"));      // missed
  EXPECT_TRUE(j["regions"][2]["hit_fraction"].is_null());  // nothing of it measured
  EXPECT_EQ(j["regions_scored"]["detected"], 1);
}

TEST_F(AppearanceScoresTest, RecolouredStableSeabedIsFalse) {
  const AppearanceScores s = scoreAppearance(truth_, change_, ChangeScoreOptions());
  // The bleach (true), the block's foot (explained), the 25-point patch (false); the lone point
  // is under compare's minimum area.
  ASSERT_EQ(s.clusters.size(), 3u);
  const AppearanceClusterScore& patch = clusterAt(s, 1, 2, -2, -1);
  EXPECT_EQ(patch.verdict, "false");
  EXPECT_EQ(patch.region, -1);
  EXPECT_EQ(s.true_clusters, 1u);
  EXPECT_EQ(s.false_clusters, 1u);
  EXPECT_DOUBLE_EQ(s.precision, 1.0 / 2.0);
  EXPECT_EQ(s.stable.significant, 26u);
  EXPECT_EQ(s.stable.significant_in_clusters, 25u);
  EXPECT_NEAR(s.stable.cluster_area_m2, 1.0, 1e-12);
  EXPECT_NEAR(s.stable.area_m2, 26 * 0.04, 1e-12);
  // 9400 core points with a colour (not the block's 100, not the 500 unmeasured) less the 332
  // near a true point (the bleach and the faint patch 12 x 12 each, the block's foot 44), give
  // or take the rows exactly 0.3 m from an edge.
  EXPECT_EQ(s.colour_measured, 9400u);
  EXPECT_NEAR(static_cast<double>(s.stable.measured), 9400.0 - 332.0, 40.0);
  EXPECT_DOUBLE_EQ(s.stable.fraction, 25.0 / static_cast<double>(s.stable.measured));

  // The patch out of the region of both visits: not scored, precision 1.
  change_.in_region.assign(change_.points.size(), 1);
  for (size_t i = 0; i < change_.points.size(); ++i) {
    if (inside(change_.points[i], 0.5, 2.5, -2.5, -0.5)) change_.in_region[i] = 0;
  }
  const AppearanceScores t = scoreAppearance(truth_, change_, ChangeScoreOptions());
  EXPECT_EQ(clusterAt(t, 1, 2, -2, -1).verdict, "outside_region");
  EXPECT_EQ(t.outside_region, 1u);
  EXPECT_EQ(t.false_clusters, 0u);
  EXPECT_DOUBLE_EQ(t.precision, 1.0);
  EXPECT_EQ(t.stable.significant_in_clusters, 0u);
}

TEST_F(AppearanceScoresTest, ColourChangeOnAFallenBlockIsExplainedByGeometry) {
  const AppearanceScores s = scoreAppearance(truth_, change_, ChangeScoreOptions());
  const AppearanceClusterScore& foot = clusterAt(s, -5.5, -4.5, -5.5, -4.5);
  EXPECT_EQ(foot.cluster.core_points.size(), 44u);  // the ring of 12 x 12 less the block's 10 x 10
  EXPECT_EQ(foot.verdict, "explained_by_geometry");
  EXPECT_EQ(truth_.regions[static_cast<size_t>(foot.region)].name, "block");
  EXPECT_EQ(foot.geometric_points, 44u);
  EXPECT_EQ(foot.albedo_points, 0u);
  EXPECT_EQ(s.explained_by_geometry, 1u);
  EXPECT_EQ(s.false_clusters, 1u);  // the recoloured patch only
  const json j = appearanceScoresJson(s, truth_);
  EXPECT_EQ(j["clusters_scored"]["explained_by_geometry"], 1);
  bool listed = false;
  for (const json& c : j["clusters"]) {
    if (c["verdict"] == "explained_by_geometry") {
      listed = true;
      EXPECT_EQ(c["region"], "block");
      EXPECT_DOUBLE_EQ(c["geometric_fraction"].get<double>(), 1.0);
    }
  }
  EXPECT_TRUE(listed) << j["clusters"];
}

TEST_F(AppearanceScoresTest, WithoutColoursNothingIsMeasured) {
  change_.delta_e.clear();
  change_.appearance_significant.clear();
  const AppearanceScores s = scoreAppearance(truth_, change_, ChangeScoreOptions());
  EXPECT_TRUE(s.clusters.empty());
  EXPECT_EQ(s.colour_measured, 0u);
  EXPECT_EQ(region(s, "bleach").status, "not_measured");
  EXPECT_EQ(s.not_measured, 3u);
}

}  // namespace
}  // namespace auv::recon::evaluate
