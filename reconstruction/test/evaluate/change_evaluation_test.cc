// The change found by `auv recon compare` scored against the simulator's change truth
// (change_truth.h, change_scores.h, change_evaluation.h): known answers on a synthetic seabed
// (which true regions are detected, missed or not measured; which clusters are true or false;
// the false area; the volume errors), malformed truth files named to the field, the paths
// without a comparison or without a truth, and the whole `evaluate` of a later survey whose
// comparison is in survey 1's reconstruction frame (moved by a known similarity).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <limits>

#include "auv/recon/common/stage_error.h"
#include "auv/recon/evaluate/change_evaluation.h"
#include "auv/recon/evaluate/change_scores.h"
#include "auv/recon/evaluate/change_truth.h"
#include "change_files.h"
#include "synthetic_survey.h"

namespace auv::recon::evaluate {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::ComparisonFixture;
using testing::rectangleRegion;
using testing::TruthRegionFixture;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Six true regions on a seabed at depth 5 (NED) and a comparison measured on a 0.2 m grid of
/// core points (x, y = -9.9 ... 9.9) with known answers.
class ChangeScoresTest : public ::testing::Test {
 protected:
  void SetUp() override {
    folder_ = testing::freshFolder("change_scores");
    truth_regions_ = {
        rectangleRegion("block", "add", -6, -4, -6, -4, 4.0, 1.0),      // 4 m², 4 m³ gained
        rectangleRegion("pit", "remove", 4, 6, -6, -4, 5.0, -0.5),      // 2 m³ lost
        rectangleRegion("growth", "grow", 4, 6, 4, 6, 4.7, 0.3),        // seen, not significant
        rectangleRegion("bleach", "albedo", -6, -4, 4, 6, 5.0, 0.0),    // a colour change
        rectangleRegion("far_block", "add", 15, 16, 15, 16, 4.0, 1.0),  // off the grid
        rectangleRegion("scuff", "grow", -0.5, 0.5, -8.5, -7.5, 5.0, -0.05)};  // too small
    testing::writeChangeTruthFiles(folder_, truth_regions_);
    truth_ = readChangeTruth(folder_ / "changes.json");
    for (int i = 0; i < 100; ++i) {
      for (int j = 0; j < 100; ++j) {
        const double x = -9.9 + 0.2 * i, y = -9.9 + 0.2 * j;
        change_.points.emplace_back(x, y, 5.0);
        change_.normals.emplace_back(0, 0, -1);  // up: + = nearer the cameras above
        double d = 0;
        bool significant = false;
        auto inside = [&](double x0, double x1, double y0, double y1) {
          return x > x0 && x < x1 && y > y0 && y < y1;
        };
        if (inside(-6, -4, -6, -4)) d = 0.9, significant = true;         // block: 3.6 m³
        if (inside(4, 6, -6, -4)) d = -0.65, significant = true;         // pit: 2.6 m³
        if (inside(4, 6, 4, 6)) d = 0.3;                                 // growth, below LoD
        if (inside(-5.2, -4.6, 4.8, 5.4)) d = 0.15, significant = true;  // on the albedo patch
        if (inside(-0.6, 0.4, 7.4, 8.4)) d = 0.2, significant = true;    // false: 25 points, 1 m²
        if (inside(8.0, 8.2, 0.0, 0.2)) d = 0.2, significant = true;     // one false point
        if (inside(-0.5, 0.5, -8.5, -7.5)) d = -0.05;                    // the scuff
        if (x > 9.0) d = kNaN, significant = false;                      // not measured
        change_.distances.push_back(d);
        change_.significant.push_back(significant ? 1 : 0);
      }
    }
    change_.core_spacing_m = 0.2;
    change_.min_cluster_area_m2 = 0.05;
  }

  const RegionScore& region(const ChangeScores& scores, const std::string& name) const {
    for (size_t k = 0; k < truth_.regions.size(); ++k) {
      if (truth_.regions[k].name == name) return scores.regions[k];
    }
    throw std::runtime_error("no region " + name);
  }

  fs::path folder_;
  std::vector<TruthRegionFixture> truth_regions_;
  ChangeTruth truth_;
  WorldChange change_;
};

TEST_F(ChangeScoresTest, TruthFilesReadBack) {
  ASSERT_EQ(truth_.regions.size(), 6u);
  EXPECT_EQ(truth_.regions[1].name, "pit");
  EXPECT_EQ(truth_.regions[1].type, "remove");
  EXPECT_FALSE(truth_.regions[3].geometric);
  EXPECT_DOUBLE_EQ(truth_.regions[0].volume_gained_m3, 4.0);
  EXPECT_DOUBLE_EQ(truth_.regions[1].max_distance_m, -0.5);
  EXPECT_DOUBLE_EQ(truth_.min_distance_m, 0.01);
  EXPECT_EQ(truth_.regions[0].points, 41u * 41u);
  ASSERT_EQ(truth_.points.size(), truth_.distances.size());
  EXPECT_EQ(truth_.region_of_point.front(), 0);
  EXPECT_EQ(truth_.region_of_point.back(), 5);
  EXPECT_NEAR(truth_.distances.back(), -0.05, 1e-7);
  EXPECT_NEAR(truth_.points.front().z(), 4.0, 1e-6);
}

TEST_F(ChangeScoresTest, RegionsClustersAndFalseAreaAsConstructed) {
  const ChangeScores s = scoreChanges(truth_, change_, ChangeScoreOptions());
  EXPECT_EQ(region(s, "block").status, "detected");
  EXPECT_EQ(region(s, "pit").status, "detected");
  EXPECT_EQ(region(s, "growth").status, "missed");
  EXPECT_EQ(region(s, "bleach").status, "appearance");
  EXPECT_EQ(region(s, "far_block").status, "not_measured");
  EXPECT_EQ(region(s, "scuff").status, "below_min_magnitude");
  EXPECT_EQ(s.detected, 2u);
  EXPECT_EQ(s.missed, 1u);
  EXPECT_EQ(s.not_measured, 1u);
  EXPECT_DOUBLE_EQ(s.recall_measured, 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(s.recall_all, 2.0 / 4.0);
  // Clusters: the block, the pit (true), the false patch, the albedo one (neither); the
  // single false point is under compare's minimum area.
  ASSERT_EQ(s.clusters.size(), 4u);
  EXPECT_EQ(s.true_clusters, 2u);
  EXPECT_EQ(s.false_clusters, 1u);
  EXPECT_DOUBLE_EQ(s.precision, 2.0 / 3.0);
  size_t appearance = 0;
  for (const ClusterScore& c : s.clusters) appearance += c.verdict == "appearance";
  EXPECT_EQ(appearance, 1u);
  // Stable surface called changed: the 25-point patch and the single point.
  EXPECT_EQ(s.stable.significant, 26u);
  EXPECT_EQ(s.stable.significant_in_clusters, 25u);
  EXPECT_NEAR(s.stable.area_m2, 26 * 0.04, 1e-12);
  EXPECT_NEAR(s.stable.cluster_area_m2, 1.0, 1e-12);
  // 9500 measured core points less the 552 within reach of a true point (the pit, the bleach
  // 12 x 12 each, the block and the growth 10 x 10 from their segments, the scuff 8 x 8), give
  // or take the rows exactly 0.3 m from an edge.
  EXPECT_NEAR(static_cast<double>(s.stable.measured), 9500.0 - 552.0, 20.0);
  EXPECT_DOUBLE_EQ(s.stable.fraction, 26.0 / static_cast<double>(s.stable.measured));
  // Distances and volumes of the detected blocks.
  const change::ChangeCluster& block = region(s, "block").measured;
  EXPECT_NEAR(block.area_m2, 4.0, 1e-9);
  EXPECT_NEAR(block.mean_distance_m, 0.9, 1e-9);
  EXPECT_NEAR(block.volume_gained_m3, 3.6, 1e-9);
  EXPECT_NEAR(region(s, "pit").measured.volume_lost_m3, 2.6, 1e-9);
  const json j = changeScoresJson(s, truth_, ChangeScoreOptions());
  const json& block_errors = j["regions"][0]["errors"];
  EXPECT_NEAR(block_errors["volume_relative"].get<double>(), -0.1, 1e-9);
  EXPECT_NEAR(block_errors["mean_distance_m"].get<double>(), -0.1, 1e-9);
  EXPECT_NEAR(block_errors["max_distance_m"].get<double>(), -0.1, 1e-9);
  EXPECT_TRUE(block_errors["volume_within_20_percent"].get<bool>());
  const json& pit_errors = j["regions"][1]["errors"];
  EXPECT_EQ(pit_errors["volume_side"], "lost");
  EXPECT_NEAR(pit_errors["volume_relative"].get<double>(), 0.3, 1e-9);
  EXPECT_NEAR(pit_errors["max_distance_m"].get<double>(), -0.15, 1e-9);
  EXPECT_FALSE(pit_errors["volume_within_20_percent"].get<bool>());
  EXPECT_FALSE(j["regions"][2].contains("errors"));  // missed: nothing measured
  EXPECT_EQ(j["regions_scored"]["detected"], 2);
  EXPECT_TRUE(j["regions_scored"]["recall_all"].is_number());
}

// At two scales the clusters are found with compare's coarse distances (min_change_m) and
// measured with the fine ones, as compare does: here the coarse pass saw the block at only
// 5 cm, under the change of interest, so no cluster there; the pit's volume is the fine one.
TEST_F(ChangeScoresTest, AtTwoScalesClustersAreFoundCoarseAndMeasuredFine) {
  change_.min_change_m = 0.1;
  change_.detection_distances = change_.distances;
  for (size_t i = 0; i < change_.points.size(); ++i) {
    const Eigen::Vector3d& p = change_.points[i];
    if (p.x() > -6 && p.x() < -4 && p.y() > -6 && p.y() < -4) change_.detection_distances[i] = 0.05;
    if (p.x() > 4 && p.x() < 6 && p.y() > -6 && p.y() < -4) change_.detection_distances[i] = -0.4;
  }
  const ChangeScores s = scoreChanges(truth_, change_, ChangeScoreOptions());
  EXPECT_EQ(region(s, "pit").status, "detected");
  bool pit = false;
  for (const ClusterScore& c : s.clusters) {
    const Eigen::Vector3d& at = c.cluster.centroid;
    EXPECT_FALSE(at.x() > -6 && at.x() < -4 && at.y() > -6 && at.y() < -4) << "on the block";
    if (c.verdict == "true") {
      pit = true;
      EXPECT_NEAR(c.cluster.volume_lost_m3, 100 * 0.65 * 0.04, 1e-9);  // fine, not 0.4 m
    }
  }
  EXPECT_TRUE(pit);
}

// At two scales with compare's growth (grow_regions), a region takes the linked points
// significant at the fine scale: the pit's coarse pass flagged only its middle.
TEST_F(ChangeScoresTest, AtTwoScalesRegionsGrowAtTheFineScaleAsCompareRecorded) {
  change_.detection_distances = change_.distances;
  change_.measuring_significant = change_.significant;  // the fine flags
  for (size_t i = 0; i < change_.points.size(); ++i) {
    const Eigen::Vector3d& p = change_.points[i];
    const bool pit = p.x() > 4 && p.x() < 6 && p.y() > -6 && p.y() < -4;
    const bool middle = p.x() > 4.6 && p.x() < 5.4 && p.y() > -5.4 && p.y() < -4.6;
    if (pit && !middle) change_.significant[i] = 0;
  }
  const auto pitPoints = [this] {
    for (const ClusterScore& c : scoreChanges(truth_, change_, ChangeScoreOptions()).clusters) {
      if (c.cluster.mean_distance_m < 0) return c.cluster.core_points.size();
    }
    return size_t{0};
  };
  EXPECT_EQ(pitPoints(), 16u);
  change_.grow_regions = true;
  EXPECT_EQ(pitPoints(), 100u);
}

TEST_F(ChangeScoresTest, RegionsTestedFamilyWiseAsCompareRecorded) {
  auto falseClusters = [this] {
    int count = 0;
    for (const ClusterScore& c : scoreChanges(truth_, change_, ChangeScoreOptions()).clusters)
      count += c.verdict == "false" ? 1 : 0;
    return count;
  };
  ASSERT_EQ(falseClusters(), 1) << "the 1 m² patch of 0.2 m";
  change_.region_confidence = 0.95;  // compare's options, as report.json records them
  change_.region_footprint_m2 = 0.04;
  EXPECT_EQ(falseClusters(), 1) << "an older compare's file has no levels of detection: no test";
  // LoD 0.1 m: the patch is z 3.9, under the bound over ~9 500 measurements (4.5); the block
  // and the pit stand.
  change_.levels_of_detection.assign(change_.points.size(), 0.1);
  EXPECT_EQ(falseClusters(), 0);
  const ChangeScores s = scoreChanges(truth_, change_, ChangeScoreOptions());
  EXPECT_EQ(region(s, "block").status, "detected");
  EXPECT_EQ(region(s, "pit").status, "detected");
}

TEST_F(ChangeScoresTest, OnlyTheWellImagedRegionCounts) {
  // The pit's side of the site imaged badly by one visit: its core points out of the region.
  change_.in_region.assign(change_.points.size(), 1);
  for (size_t i = 0; i < change_.points.size(); ++i) {
    if (change_.points[i].x() > 3.0 && change_.points[i].y() < -3.0) change_.in_region[i] = 0;
  }
  const ChangeScores s = scoreChanges(truth_, change_, ChangeScoreOptions());
  EXPECT_EQ(region(s, "pit").status, "not_measured");
  EXPECT_EQ(s.detected, 1u);
  EXPECT_EQ(s.not_measured, 2u);
  EXPECT_DOUBLE_EQ(s.recall_measured, 1.0 / 2.0);
  EXPECT_EQ(s.true_clusters, 1u);
  EXPECT_DOUBLE_EQ(s.precision, 1.0 / 2.0);
  size_t outside = 0;
  for (const ClusterScore& c : s.clusters) outside += c.verdict == "outside_region";
  EXPECT_EQ(outside, 1u);
}

TEST_F(ChangeScoresTest, ClustersUnderTheMinimumAreaAreNotScored) {
  ChangeScoreOptions options;
  options.min_cluster_area_m2 = 2.0;  // keeps the block and the pit (4 m² each)
  const ChangeScores s = scoreChanges(truth_, change_, options);
  EXPECT_EQ(s.clusters.size(), 2u);
  EXPECT_DOUBLE_EQ(s.precision, 1.0);
  EXPECT_EQ(s.stable.significant_in_clusters, 0u);
  EXPECT_EQ(s.stable.significant, 26u);
}

TEST(ChangeScoreOptions, OutOfRangeNamed) {
  ChangeScoreOptions options;
  options.min_hit_fraction = 0;
  try {
    options.check();
    FAIL() << "accepted min_hit_fraction = 0";
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("min_hit_fraction"), std::string::npos) << e.what();
  }
  options = ChangeScoreOptions();
  options.match_radius_m = -1;
  EXPECT_THROW(options.check(), OptionError);
}

/// The error message of reading `folder`/changes.json, or "" when it reads.
std::string readError(const fs::path& folder) {
  try {
    readChangeTruth(folder / "changes.json");
  } catch (const StageError& e) {
    return e.what();
  }
  return "";
}

void editJson(const fs::path& file, const std::function<void(json&)>& edit) {
  json j;
  {
    std::ifstream in(file);
    j = json::parse(in);
  }
  edit(j);
  std::ofstream(file) << j.dump(2);
}

TEST(ChangeTruthFile, MalformedNamedByFileAndField) {
  const fs::path folder = testing::freshFolder("change_truth_malformed");
  const std::vector<TruthRegionFixture> regions = {
      rectangleRegion("block", "add", 0, 1, 0, 1, 4.0, 1.0),
      rectangleRegion("patch", "albedo", 3, 4, 0, 1, 5.0, 0.0)};
  testing::writeChangeTruthFiles(folder, regions);
  ASSERT_EQ(readError(folder), "");
  const fs::path file = folder / "changes.json";

  editJson(file, [](json& j) { j["regions"][1]["type"] = "melt"; });
  std::string error = readError(folder);
  EXPECT_NE(error.find(file.string() + ": regions[1].type: expected add, remove"),
            std::string::npos)
      << error;

  testing::writeChangeTruthFiles(folder, regions);
  editJson(file, [](json& j) { j["regions"][0].erase("max_distance_m"); });
  error = readError(folder);
  EXPECT_NE(error.find(file.string() + ": regions[0].max_distance_m: missing"), std::string::npos)
      << error;

  testing::writeChangeTruthFiles(folder, regions);
  editJson(file, [](json& j) { j["regions"][0]["centroid"] = {1, 2}; });
  EXPECT_NE(readError(folder).find("regions[0].centroid: expected [x, y, z]"), std::string::npos);

  testing::writeChangeTruthFiles(folder, regions);
  editJson(file, [](json& j) { j["format"] = "auv-sim-changes 2"; });
  EXPECT_NE(readError(folder).find("format: expected \"auv-sim-changes 1\""), std::string::npos);

  // The points: a region index that is not one, a count that disagrees, a missing property.
  testing::writeChangeTruthFiles(folder, regions);
  editJson(file, [](json& j) { j["regions"].erase(1); });
  error = readError(folder);
  EXPECT_NE(error.find((folder / "changes.ply").string() + ": vertex "), std::string::npos)
      << error;
  EXPECT_NE(error.find("region 1 is not an index of the 1 regions"), std::string::npos) << error;

  testing::writeChangeTruthFiles(folder, regions);
  editJson(file, [](json& j) { j["regions"][0]["points"] = 7; });
  error = readError(folder);
  EXPECT_NE(error.find("changes.json's regions[0].points says 7"), std::string::npos) << error;

  testing::writeChangeTruthFiles(folder, regions);
  scene::PlyData no_region;
  no_region.positions = {Eigen::Vector3d(0, 0, 0)};
  no_region.scalars = {{"distance", {0.5f}}};
  scene::writePly(folder / "changes.ply", no_region);
  EXPECT_NE(readError(folder).find("changes.ply: no vertex property \"region\""),
            std::string::npos);

  fs::remove(folder / "changes.ply");
  EXPECT_NE(readError(folder).find("changes.ply: not found"), std::string::npos);
}

/// The synthetic survey (synthetic_survey.h) as survey 1, a copy of it as survey 2 in a run
/// where a 1 x 1 x 0.5 m pile appeared, and compare's output in survey 1's frame.
class ChangeEvaluationTest : public testing::SyntheticSurvey {
 protected:
  /// `with_stain`: also a bleached stain on the seabed (x -0.6..0.2, y -1.2..-0.4), an albedo
  /// region of the truth.
  void makeLaterSurvey(bool with_stain = false) {
    survey2_ = root_ / "survey2";
    run2_ = root_ / "run2";
    fs::copy(survey_, survey2_, fs::copy_options::recursive);
    fs::copy(run_, run2_, fs::copy_options::recursive);
    std::ofstream(survey_ / "simulation.json") << json({{"ground_truth_run", "../run"}});
    std::ofstream(survey2_ / "simulation.json") << json({{"ground_truth_run", "../run2"}});
    // The later world: the pile on the seabed, x -2..-1, y -0.6..0.4, top at depth 4.5.
    open3d::geometry::TriangleMesh later = world_;
    auto pile = open3d::geometry::TriangleMesh::CreateBox(1.0, 1.0, 0.5);
    pile->Translate(Eigen::Vector3d(-2.0, -0.6, 4.5));
    later += *pile;
    scene::PlyData ply;
    ply.positions = later.vertices_;
    for (const auto& t : later.triangles_) {
      ply.triangles.push_back(
          {static_cast<uint32_t>(t(0)), static_cast<uint32_t>(t(1)), static_cast<uint32_t>(t(2))});
    }
    scene::writePly(run2_ / "ground_truth" / "world.ply", ply);
    std::vector<TruthRegionFixture> regions = {
        rectangleRegion("pile", "add", -2, -1, -0.6, 0.4, 4.5, 0.5)};
    if (with_stain)
      regions.push_back(rectangleRegion("stain", "albedo", -0.6, 0.2, -1.2, -0.4, 5.0, 0));
    testing::writeChangeTruthFiles(run2_ / "ground_truth", regions);
  }

  /// compare's core points every 0.2 m of the seabed under the cameras (not on the rock), the
  /// pile's +0.5 m significant, all in survey 1's reconstruction frame (sim_ inverse).
  /// `with_appearance`: also the colour change (ΔE 2, the stain's 16 core points ΔE 20 and
  /// significant, the pile's not compared); without, as an older compare wrote changes.ply.
  void writeLaterComparison(bool with_appearance = false) {
    ComparisonFixture c;
    const Similarity to_model = sim_.inverse();
    for (int i = 0; i < 30; ++i) {
      for (int j = 0; j < 14; ++j) {
        const double x = -2.9 + 0.2 * i, y = -1.3 + 0.2 * j;
        if (x > 0.4 && x < 1.6 && y > 0.7) continue;  // the rock
        const bool on_pile = x > -2 && x < -1 && y > -0.6 && y < 0.4;
        c.add(to_model.apply(Eigen::Vector3d(x, y, 5.0)), (on_pile ? 0.5 : 0.0) / sim_.scale,
              on_pile, to_model.rotation * Eigen::Vector3d(0, 0, -1));
        const bool on_stain = x > -0.6 && x < 0.2 && y > -1.2 && y < -0.4;
        c.delta_e.push_back(on_pile ? kNaN : on_stain ? 20.0 : 2.0);
        c.appearance_significant.push_back(on_stain);
      }
    }
    if (!with_appearance) c.delta_e.clear(), c.appearance_significant.clear();
    const double spacing = 0.2 / sim_.scale;  // compare ran in the model's frame
    testing::writeComparison(
        survey2_, c,
        {{"survey_1", survey_.string()},
         {"registration", {{"rms_m", 0.004}, {"overlap", 0.9}, {"stable_fraction", 0.97}}},
         {"options",
          {{"core_spacing_m", spacing}, {"min_cluster_area_m2", 0.05 / (sim_.scale * sim_.scale)}}},
         {"clusters", json::array({json::object()})},
         {"appearance", {{"measured", true}, {"clusters", json::array({json::object()})}}}});
  }

  fs::path survey2_, run2_;
};

TEST_F(ChangeEvaluationTest, NoCompareOutputSaysWhy) {
  const json r = evaluateSurvey(Survey(survey_), run_, quickOptions());
  EXPECT_EQ(r["change"]["status"], "not evaluated");
  EXPECT_NE(r["change"]["why"].get<std::string>().find("run auv recon compare <survey-1> " +
                                                       survey_.string()),
            std::string::npos)
      << r["change"];
  EXPECT_GT(fscore(r, "dense", 0.05), 0.99);  // evaluated as before
  std::ifstream in(survey_ / "report.json");
  EXPECT_EQ(json::parse(in)["stages"]["evaluate"]["change_status"], "not evaluated");
}

TEST_F(ChangeEvaluationTest, NoTruthSaysWhy) {
  makeLaterSurvey();
  writeLaterComparison();
  fs::remove(run2_ / "ground_truth" / "changes.json");
  const json change = evaluateChange(Survey(survey2_), run2_, WellImagedSamples(), quickOptions());
  EXPECT_EQ(change["status"], "not evaluated");
  EXPECT_EQ(change["why"], "the ground truth has no changes.json (" +
                               (run2_ / "ground_truth" / "changes.json").string() + ")");
  EXPECT_EQ(changeSummary(change), change["why"].get<std::string>());
}

TEST_F(ChangeEvaluationTest, MissingSurvey1SaysWhy) {
  makeLaterSurvey();
  writeLaterComparison();
  EvaluateOptions options = quickOptions();
  options.survey_1 = (root_ / "nowhere").string();
  const json change = evaluateChange(Survey(survey2_), run2_, WellImagedSamples(), options);
  EXPECT_EQ(change["status"], "not evaluated");
  EXPECT_NE(change["why"].get<std::string>().find("nowhere (--survey-1) not found"),
            std::string::npos)
      << change;
}

TEST_F(ChangeEvaluationTest, LaterSurveyScoredInTheWorldFrame) {
  makeLaterSurvey();
  writeLaterComparison();
  const json r = evaluateSurvey(Survey(survey2_), run2_, quickOptions());
  const json& change = r["change"];
  ASSERT_EQ(change["status"], "evaluated") << change;
  EXPECT_EQ(change["survey_1"]["path"], survey_.string());
  EXPECT_LT(change["survey_1"]["alignment"]["camera_position_error_median_m"].get<double>(), 1e-6);
  EXPECT_NEAR(change["survey_1"]["alignment"]["scale"].get<double>(), sim_.scale, 1e-6);
  EXPECT_NEAR(change["compare"]["core_spacing_m"].get<double>(), 0.2, 1e-9);
  EXPECT_DOUBLE_EQ(change["registration"]["rms_m"].get<double>(), 0.004);
  EXPECT_GT(change["region"]["core_points_in_both"].get<size_t>(), 200u);
  const json& pile = change["regions"][0];
  EXPECT_EQ(pile["status"], "detected") << pile;
  EXPECT_DOUBLE_EQ(pile["hit_fraction"].get<double>(), 1.0);
  EXPECT_EQ(change["clusters_scored"]["true"], 1);
  EXPECT_EQ(change["clusters_scored"]["false"], 0);
  EXPECT_DOUBLE_EQ(change["clusters_scored"]["precision"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(change["regions_scored"]["recall_measured"].get<double>(), 1.0);
  EXPECT_EQ(change["stable"]["core_points_significant"], 0);
  // 25 core points x 0.5 m x (0.2 m)² = 0.5 m³, the pile's volume: scale and frame undone.
  EXPECT_NEAR(pile["measured"]["volume_gained_m3"].get<double>(), 0.5, 1e-5);
  EXPECT_NEAR(pile["errors"]["volume_relative"].get<double>(), 0.0, 1e-5);
  EXPECT_NEAR(pile["measured"]["mean_distance_m"].get<double>(), 0.5, 1e-6);
  EXPECT_NEAR(pile["measured"]["centroid"][0].get<double>(), -1.5, 1e-6);
  // The later world (ground_truth/world.ply, with the pile) is what survey 2 is measured on.
  EXPECT_EQ(r["world_mesh"], (run2_ / "ground_truth" / "world.ply").string());
  std::ifstream in(survey2_ / "report.json");
  const json section = json::parse(in)["stages"]["evaluate"];
  EXPECT_DOUBLE_EQ(section["change_recall"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(section["change_precision"].get<double>(), 1.0);
  EXPECT_NE(changeSummary(change).find("1 of 1 measured true regions detected"), std::string::npos)
      << changeSummary(change);
}

TEST_F(ChangeEvaluationTest, AppearanceScoredInTheWorldFrame) {
  makeLaterSurvey(true);
  writeLaterComparison(true);
  const json r = evaluateSurvey(Survey(survey2_), run2_, quickOptions());
  const json& change = r["change"];
  ASSERT_EQ(change["status"], "evaluated") << change;
  const json& a = change["appearance"];
  ASSERT_EQ(a["status"], "evaluated") << a;
  ASSERT_EQ(a["regions"].size(), 1u);
  EXPECT_EQ(a["regions"][0]["name"], "stain");
  EXPECT_EQ(a["regions"][0]["status"], "detected") << a["regions"][0];
  EXPECT_EQ(a["clusters_scored"]["true"], 1);
  EXPECT_EQ(a["clusters_scored"]["false"], 0);
  EXPECT_DOUBLE_EQ(a["clusters_scored"]["precision"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(a["regions_scored"]["recall_measured"].get<double>(), 1.0);
  EXPECT_EQ(a["stable"]["core_points_significant"], 0);
  // 16 core points x (0.2 m)² in the world: the scale of survey 1's frame undone.
  ASSERT_EQ(a["clusters"].size(), 1u);
  EXPECT_NEAR(a["clusters"][0]["area_m2"].get<double>(), 0.64, 1e-6);
  EXPECT_NEAR(a["clusters"][0]["centroid"][0].get<double>(), -0.2, 1e-6);
  EXPECT_EQ(a["compare"]["clusters_in_report"], 1);
  EXPECT_EQ(a["compare"]["clusters_rebuilt"], 1);
  // The stain in the shape's list is the appearance's, as before.
  EXPECT_EQ(change["regions"][1]["status"], "appearance");
  std::ifstream in(survey2_ / "report.json");
  const json section = json::parse(in)["stages"]["evaluate"];
  EXPECT_EQ(section["change_appearance_status"], "evaluated");
  EXPECT_DOUBLE_EQ(section["change_appearance_precision"].get<double>(), 1.0);
  EXPECT_NE(changeSummary(change).find("appearance: 1 of 1 measured albedo regions detected"),
            std::string::npos)
      << changeSummary(change);
}

TEST_F(ChangeEvaluationTest, OlderCompareWithoutAppearanceScoresTheShapeAlone) {
  makeLaterSurvey(true);
  writeLaterComparison(true);
  const json with = evaluateSurvey(Survey(survey2_), run2_, quickOptions())["change"];
  writeLaterComparison(false);
  const json without = evaluateSurvey(Survey(survey2_), run2_, quickOptions())["change"];
  ASSERT_EQ(without["status"], "evaluated") << without;
  EXPECT_EQ(without["appearance"]["status"], "not evaluated");
  const std::string why = without["appearance"]["why"];
  EXPECT_NE(why.find("has no scalar_delta_e, scalar_appearance_significant"), std::string::npos)
      << why;
  EXPECT_NE(why.find("older auv recon compare"), std::string::npos) << why;
  ASSERT_EQ(with["appearance"]["status"], "evaluated");
  for (const char* key : {"regions_scored", "clusters_scored", "stable", "regions", "clusters"}) {
    EXPECT_EQ(without[key], with[key]) << key;
  }
  EXPECT_EQ(without["regions"][0]["status"], "detected");
  const std::string summary = changeSummary(without);
  EXPECT_NE(summary.find("1 of 1 measured true regions detected"), std::string::npos) << summary;
  EXPECT_NE(summary.find("appearance not evaluated: " + why), std::string::npos) << summary;
  std::ifstream in(survey2_ / "report.json");
  const json section = json::parse(in)["stages"]["evaluate"];
  EXPECT_EQ(section["change_appearance_status"], "not evaluated");
  EXPECT_FALSE(section.contains("change_appearance_precision"));
  EXPECT_DOUBLE_EQ(section["change_precision"].get<double>(), 1.0);
}

TEST_F(ChangeEvaluationTest, MalformedTruthFailsTheEvaluationNamingIt) {
  makeLaterSurvey();
  writeLaterComparison();
  const fs::path file = run2_ / "ground_truth" / "changes.json";
  editJson(file, [](json& j) { j["regions"][0]["geometric"] = "yes"; });
  try {
    evaluateSurvey(Survey(survey2_), run2_, quickOptions());
    FAIL() << "accepted a malformed changes.json";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find(file.string() + ": regions[0].geometric: expected true "
                                                         "or false"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(fs::exists(survey2_ / "evaluation.json"));  // nothing written
}

}  // namespace
}  // namespace auv::recon::evaluate
