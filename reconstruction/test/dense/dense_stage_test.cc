// The whole stage on a synthetic survey: fused cloud against the true surface, outputs,
// report, and the expected failures (which leave an earlier dense/ intact).
#include "auv/recon/dense/dense_stage.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>

#include <open3d/io/PointCloudIO.h>
#include <opencv2/imgcodecs.hpp>

#include "../support/folder_files.h"
#include "auv/recon/common/option_set.h"
#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/dense/depth_map.h"
#include "auv/recon/scene/colmap_text.h"
#include "synthetic_scene.h"

namespace fs = std::filesystem;

namespace auv::recon::dense {
namespace {

class DenseStage : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("dense_stage_" + std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_);
    options_.min_points = 1000;
    options_.neighbours.max_neighbours = 4;
  }
  void TearDown() override { fs::remove_all(root_); }

  /// A survey with sparse/ and corrected/ of the 3x3 grid over `scene`.
  Survey makeSurvey(const testing::Scene& scene, int columns = 3, int rows = 3) {
    std::vector<View> views = testing::gridViews(columns, rows, 0.35, 4.0);
    std::vector<cv::Mat> depths;
    // The sparse points come from the textured scene (SfM found them); the images may not.
    testing::Scene geometry = scene;
    geometry.textured = true;
    for (View& view : views) depths.push_back(testing::render(geometry, view));
    if (!scene.textured) {
      for (View& view : views) testing::render(scene, view);
    }
    Survey survey(root_ / "survey");
    scene::writeColmapText(testing::sparseModel(views, depths), survey.sparse());
    testing::writeImages(views, survey.corrected());
    return survey;
  }

  /// Distance of a point to the scene's surface (plane or sphere), m.
  static double surfaceDistance(const testing::Scene& scene, const Eigen::Vector3d& p) {
    double d = std::abs(scene.plane_normal.dot(p));
    if (scene.with_sphere) {
      d = std::min(d, std::abs((p - scene.sphere_center).norm() - scene.sphere_radius));
    }
    return d;
  }

  fs::path root_;
  DenseStageOptions options_;
};

// Tolerances: median distance of the fused points to the true surface < 1 cm at 4 m
// (0.25 %), 95th percentile < 4 cm; > 60 % of the ground area under the central camera
// covered; normals on the plane within 10 deg (median).
TEST_F(DenseStage, FusedCloudLiesOnTheTrueSurface) {
  const testing::Scene scene;
  const Survey survey = makeSurvey(scene);
  const DenseStageResult summary = runDenseStage(survey, options_);
  EXPECT_EQ(summary.registered_images, 9u);
  EXPECT_EQ(summary.depth_maps, 9u);
  EXPECT_EQ(summary.width, 240);

  const fs::path ply = survey.dense() / "fused.ply";
  open3d::geometry::PointCloud cloud;
  ASSERT_TRUE(open3d::io::ReadPointCloud(ply.string(), cloud));
  ASSERT_EQ(cloud.points_.size(), summary.points);
  ASSERT_TRUE(cloud.HasNormals());
  ASSERT_TRUE(cloud.HasColors());
  std::vector<double> distances, plane_angles;
  for (size_t i = 0; i < cloud.points_.size(); ++i) {
    const Eigen::Vector3d& p = cloud.points_[i];
    distances.push_back(surfaceDistance(scene, p));
    if ((p - scene.sphere_center).norm() > scene.sphere_radius + 0.2) {
      plane_angles.push_back(
          std::acos(std::clamp(cloud.normals_[i].dot(scene.plane_normal), -1.0, 1.0)) * 180 / M_PI);
    }
  }
  std::sort(distances.begin(), distances.end());
  std::sort(plane_angles.begin(), plane_angles.end());
  const double median = distances[distances.size() / 2];
  const double p95 = distances[distances.size() * 95 / 100];
  const double angle = plane_angles[plane_angles.size() / 2];
  std::printf(
      "%zu points; distance to the surface: median %.4f m, 95%% %.4f m; normals on the "
      "plane: median %.1f deg; %zu of %zu depths dropped as inconsistent\n",
      distances.size(), median, p95, angle, summary.depths_inconsistent, summary.depths_fused);
  EXPECT_LT(median, 0.01);
  EXPECT_LT(p95, 0.04);
  EXPECT_LT(angle, 10.0);
  // Coverage: cells of 5 cm over the central camera's footprint (about 2.2 x 1.6 m).
  std::set<std::pair<int, int>> cells;
  for (const Eigen::Vector3d& p : cloud.points_) {
    if (std::abs(p.x()) < 1.0 && std::abs(p.y()) < 0.7) {
      cells.insert(
          {static_cast<int>(std::floor(p.x() / 0.05)), static_cast<int>(std::floor(p.y() / 0.05))});
    }
  }
  EXPECT_GT(cells.size(), 0.6 * 40 * 28) << "cells covered";

  // Contributing images: >= 1 + min_consistent per point, ids of the model.
  const PointViews images = readPointViews(survey.dense() / "fused_views.bin");
  ASSERT_EQ(images.size(), cloud.points_.size());
  for (size_t i = 0; i < images.size(); ++i) {
    const std::vector<uint32_t> ids = images.of(i);
    ASSERT_GE(ids.size(), 1u + options_.fusion.min_consistent);
    for (const uint32_t id : ids) ASSERT_TRUE(id >= 1 && id <= 9) << id;
  }
  // Depth maps, neighbours and the report.
  EXPECT_TRUE(fs::exists(survey.dense() / "depth_maps" / "cam" / "image_5.depth.bin"));
  EXPECT_EQ(readDenseArray(survey.dense() / "depth_maps" / "cam" / "image_5.depth.bin").size(),
            cv::Size(240, 180));
  EXPECT_TRUE(fs::exists(survey.dense() / "neighbours.csv"));
  const nlohmann::json report = readReport(survey.report());
  ASSERT_TRUE(report["stages"].contains("dense"));
  EXPECT_EQ(report["stages"]["dense"]["points"].get<size_t>(), summary.points);
  EXPECT_GT(report["stages"]["dense"]["matching"]["peak_memory_mb"].get<double>(), 0);
}

// Masks (masks/mask.h): a masked pixel gets no depth; a wrong-size mask is named.
TEST_F(DenseStage, MaskedPixelsGetNoDepth) {
  const Survey survey = makeSurvey(testing::Scene());
  const cv::Size size = cv::imread((survey.corrected() / "cam" / "image_5.png").string()).size();
  ASSERT_FALSE(size.empty());
  cv::Mat mask(size, CV_8U, cv::Scalar(255));
  mask(cv::Rect(0, 0, size.width / 2, size.height)).setTo(0);
  fs::create_directories(survey.root() / "masks");
  ASSERT_TRUE(cv::imwrite((survey.root() / "masks" / "cam.png").string(), mask));
  const DenseStageResult summary = runDenseStage(survey, options_);
  EXPECT_EQ(summary.masked_depth_maps, summary.depth_maps);
  const cv::Mat depth = readDenseArray(survey.dense() / "depth_maps" / "cam" / "image_5.depth.bin");
  const int half = depth.cols / 2;
  EXPECT_EQ(cv::countNonZero(depth(cv::Rect(0, 0, half, depth.rows))), 0);
  EXPECT_GT(cv::countNonZero(depth(cv::Rect(half, 0, depth.cols - half, depth.rows))),
            depth.total() / 4);
  EXPECT_EQ(readReport(survey.report())["stages"]["dense"]["masked_depth_maps"].get<size_t>(),
            summary.depth_maps);

  cv::imwrite((survey.root() / "masks" / "cam.png").string(), cv::Mat(10, 10, CV_8U));
  try {
    runDenseStage(survey, options_);
    FAIL() << "a wrong-size mask was accepted";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("masks/cam.png"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("10x10"), std::string::npos) << e.what();
  }
}

TEST_F(DenseStage, MaxImageSizeScalesTheDepthMaps) {
  const Survey survey = makeSurvey(testing::Scene(), 2, 2);
  options_.max_image_size = 120;
  options_.min_points = 100;
  const DenseStageResult summary = runDenseStage(survey, options_);
  EXPECT_EQ(summary.width, 120);
  EXPECT_EQ(summary.height, 90);
  EXPECT_GT(summary.points, 100u);
}

TEST_F(DenseStage, TooFewRegisteredImages) {
  const Survey survey = makeSurvey(testing::Scene(), 1, 1);
  try {
    runDenseStage(survey, options_);
    FAIL() << "no error";
  } catch (const StageError& e) {
    EXPECT_EQ(e.stage(), "dense");
    EXPECT_NE(std::string(e.what()).find("1 registered images"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(survey.dense()));
}

// Images without texture give no depth: the stage stops naming the cause, and the dense/
// folder of an earlier run is left as it was.
TEST_F(DenseStage, EmptyCloudFailsAndKeepsTheEarlierOutput) {
  testing::Scene flat;
  flat.textured = false;
  const Survey survey = makeSurvey(flat);
  fs::create_directories(survey.dense());
  std::ofstream(survey.dense() / "fused.ply") << "earlier";
  try {
    runDenseStage(survey, options_);
    FAIL() << "no error";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("dense: the fused cloud has 0 points"), std::string::npos)
        << e.what();
  }
  std::ifstream in(survey.dense() / "fused.ply");
  std::string content;
  std::getline(in, content);
  EXPECT_EQ(content, "earlier");
  for (const auto& entry : fs::directory_iterator(survey.root())) {
    EXPECT_EQ(entry.path().filename().string().find(".dense.staging"), std::string::npos)
        << "staging folder left behind: " << entry.path();
  }
}

using test_support::filesOf;

// Depth maps per view shard (cluster/README.md): the merge fuses them into the same files as
// the whole run, on any number of shards, more shards than masters included.
TEST_F(DenseStage, MergedShardsEqualTheWholeRun) {
  const testing::Scene scene;
  const Survey survey = makeSurvey(scene);
  const DenseStageResult whole = runDenseStage(survey, options_);
  const auto expected = filesOf(survey.dense());
  ASSERT_EQ(expected.size(), whole.depth_maps + 3);  // + fused.ply, fused_views.bin, neighbours
  for (int count : {1, 2, static_cast<int>(whole.masters) + 2}) {
    SCOPED_TRACE(count);
    fs::remove_all(survey.dense());
    size_t maps = 0;
    for (int index = 0; index < count; ++index) {
      maps += runDenseShard(survey, options_, {index, count});
    }
    EXPECT_EQ(maps, whole.depth_maps);
    EXPECT_FALSE(fs::exists(survey.dense()));  // shards write only their own folders
    const DenseStageResult merged = mergeDenseShards(survey, options_, count);
    EXPECT_EQ(merged.points, whole.points);
    EXPECT_EQ(merged.depth_pixels, whole.depth_pixels);
    EXPECT_EQ(merged.width, whole.width);
    EXPECT_TRUE(filesOf(survey.dense()) == expected) << "sharded dense/ differs from the whole run";
    EXPECT_FALSE(fs::exists(survey.root() / ".shards" / "dense"));
    EXPECT_EQ(readReportSection(survey.report(), "dense").value("shards", 1), count);
  }
}

// A merge with a shard missing, or a shard of another sparse model, names it and leaves the
// earlier dense/ as it was.
TEST_F(DenseStage, MergeRefusesMissingAndStaleShards) {
  const testing::Scene scene;
  const Survey survey = makeSurvey(scene);
  runDenseStage(survey, options_);
  const auto earlier = filesOf(survey.dense());
  runDenseShard(survey, options_, {0, 2});
  try {
    mergeDenseShards(survey, options_, 2);
    FAIL() << "merged without shard 1";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("shard 1 of 2 has not run"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("--shard 1/2"), std::string::npos) << e.what();
  }
  runDenseShard(survey, options_, {1, 2});
  const fs::path shard_json = survey.root() / ".shards" / "dense" / "1-of-2" / "shard.json";
  std::ofstream(shard_json) << R"({"masters": ["elsewhere.png"]})";  // another model's shard
  try {
    mergeDenseShards(survey, options_, 2);
    FAIL() << "merged a shard of other masters";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("shard 1 of 2 holds the depth maps of other masters"),
              std::string::npos)
        << e.what();
  }
  std::ofstream(shard_json) << "[1, 2]";
  try {
    mergeDenseShards(survey, options_, 2);
    FAIL() << "merged a shard.json that is no object";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("not a shard's JSON object"), std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(filesOf(survey.dense()) == earlier);
}

TEST_F(DenseStage, MissingInputsAreNamed) {
  Survey survey(root_ / "nothing");
  try {
    runDenseStage(survey, options_);
    FAIL() << "no error";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("sfm"), std::string::npos) << e.what();
  }
  // A model whose image file is missing: the error names the file.
  const Survey full = makeSurvey(testing::Scene(), 2, 1);
  fs::remove(full.corrected() / "cam" / "image_2.png");
  try {
    runDenseStage(full, options_);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("image_2.png"), std::string::npos) << e.what();
  }
}

TEST_F(DenseStage, DistortedCamerasAreRefused) {
  const Survey survey = makeSurvey(testing::Scene(), 2, 1);
  scene::Reconstruction model = scene::readColmapText(survey.sparse());
  model.cameras.begin()->second.model = scene::CameraModel::OPENCV;
  model.cameras.begin()->second.distortion = {0.1, 0, 0, 0};
  EXPECT_THROW(densify(model, survey.corrected(), survey.dense(), options_), StageError);
}

TEST_F(DenseStage, OptionsAreChecked) {
  DenseStageOptions options;
  options.max_image_size = 10;
  EXPECT_THROW(options.check(), OptionError);
  options = DenseStageOptions();
  options.matcher.p2 = 1;  // below p1
  try {
    options.check();
    FAIL() << "no error";
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("p2 = 1"), std::string::npos) << e.what();
  }
}

TEST(DenseOptionsBind, TakesFlagsAndTheConfigSection) {
  const fs::path file =
      fs::temp_directory_path() / ("dense_bind_" + std::to_string(::getpid()) + ".yaml");
  std::ofstream(file) << "dense:\n  max_image_size: 512\n  directions: 4\n"
                         "  keep_depth_maps: false\n  min_consistent: 3\n";
  DenseStageOptions options;
  OptionSet set("dense");
  options.bind(set);
  ASSERT_TRUE(set.parse({"--config", file.string(), "--max-neighbours", "5", "--p2", "300"}));
  EXPECT_EQ(options.max_image_size, 512);
  EXPECT_EQ(options.matcher.directions, 4);
  EXPECT_FALSE(options.keep_depth_maps);
  EXPECT_EQ(options.fusion.min_consistent, 3);
  EXPECT_EQ(options.neighbours.max_neighbours, 5);
  EXPECT_EQ(options.matcher.p2, 300);
  EXPECT_EQ(options.matcher.window_radius, MatcherOptions().window_radius);  // default kept
  EXPECT_NO_THROW(options.check());
  std::ofstream(file) << "dense:\n  max_neighbors: 5\n";
  try {
    set.applyConfigFile(file);
    FAIL() << "an unknown key was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("dense.max_neighbors"), std::string::npos) << e.what();
  }
  fs::remove(file);
}

}  // namespace
}  // namespace auv::recon::dense
