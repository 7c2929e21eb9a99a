// The sfm stage over a survey folder: Sceaux castle (real photos) end to end through the
// features and match stages, and the expected failures that must leave sparse/ as it was.
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/features/features_stage.h"
#include "auv/recon/features/match_stage.h"
#include "auv/recon/scene/colmap_text.h"
#include "auv/recon/sfm/navigation.h"
#include "auv/recon/sfm/sfm_stage.h"

namespace auv::recon::sfm {
namespace {

namespace fs = std::filesystem;

fs::path freshFolder(const std::string& name) {
  const fs::path folder =
      fs::temp_directory_path() / ("auv_sfm_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(folder);
  fs::create_directories(folder);
  return folder;
}

void writeCorrectedYaml(const fs::path& file, int width, int height, double f, double cx,
                        double cy, const std::string& prior_source = "") {
  cv::FileStorage storage(file.string(), cv::FileStorage::WRITE);
  storage << "image_width" << width << "image_height" << height;
  storage << "camera_matrix" << (cv::Mat_<double>(3, 3) << f, 0, cx, 0, f, cy, 0, 0, 1);
  storage << "distortion_coefficients" << cv::Mat::zeros(1, 5, CV_64F);
  storage << "rms_reprojection_error_px" << 0.0;
  if (!prior_source.empty()) storage << "prior_source" << prior_source;
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const StageError& e) {
    return e.what();
  }
  return "";
}

// Sceaux castle, 11 photos 2832x2128, fixed intrinsics from K.txt. Run at HALF resolution
// (1416x1064, K scaled) to keep the test short: feature extraction and matching at full size
// take minutes on two shared cores. The full-resolution figures are in bench/sfm.
TEST(SfmStage, SceauxCastleRegistersAllElevenImagesBelowOnePixel) {
  const fs::path data = fs::path(AUV_RECON_SHARED_DATA) / "sceaux_castle" / "images";
  if (!fs::exists(data / "K.txt")) GTEST_SKIP() << "Sceaux castle data absent: " << data;
  const fs::path root = freshFolder("sceaux");
  const Survey survey(root);
  fs::create_directories(survey.corrected() / "castle");
  size_t images = 0;
  for (const auto& entry : fs::directory_iterator(data)) {
    if (entry.path().extension() != ".JPG") continue;
    cv::Mat full = cv::imread(entry.path().string(), cv::IMREAD_COLOR);
    ASSERT_FALSE(full.empty()) << entry.path();
    cv::Mat half;
    cv::resize(full, half, cv::Size(full.cols / 2, full.rows / 2), 0, 0, cv::INTER_AREA);
    cv::imwrite((survey.corrected() / "castle" / (entry.path().stem().string() + ".png")).string(),
                half);
    ++images;
  }
  ASSERT_EQ(images, 11u);
  // K.txt: f 2905.88, c (1416, 1064) at full size; pixel centres: c' = (c + 0.5) / 2 - 0.5.
  writeCorrectedYaml(survey.corrected() / "castle.yaml", 1416, 1064, 2905.88 / 2, 707.75, 531.75);

  features::FeaturesStageOptions extraction;
  extraction.threads = 2;
  features::runFeaturesStage(survey, extraction);
  features::MatchStageOptions matching;
  matching.threads = 2;
  features::runMatchStage(survey, matching);

  SfmStageOptions options;
  const SfmStageResult summary = runSfmStage(survey, options);
  EXPECT_EQ(summary.images_total, 11u);
  EXPECT_EQ(summary.images_registered, 11u);
  EXPECT_LT(summary.mean_reprojection_error_px, 1.0);
  EXPECT_GT(summary.points, 2000u);

  // What is on disk is what was reconstructed.
  const scene::Reconstruction written = scene::readColmapText(survey.sparse());
  EXPECT_EQ(written.images.size(), summary.images_registered);
  EXPECT_EQ(written.points.size(), summary.points);
  EXPECT_NEAR(written.meanReprojectionError(), summary.mean_reprojection_error_px, 0.01);
  EXPECT_EQ(written.cameras.size(), 1u);
  EXPECT_NEAR(written.cameras.at(1).fx, 2905.88 / 2, 1e-6);
  EXPECT_TRUE(fs::exists(survey.sparse() / "points.ply"));
  EXPECT_TRUE(fs::exists(survey.sparse() / "cameras.ply"));
  const nlohmann::json report = readReport(survey.report());
  EXPECT_EQ(report["stages"]["sfm"]["images_registered"], summary.images_registered);
  EXPECT_TRUE(report["stages"]["sfm"]["seconds_per_substage"].contains("global_ba"));

  // Bad input after a good run: the earlier sparse/ stays as it was.
  const auto before = fs::last_write_time(survey.sparse() / "images.txt");
  fs::rename(survey.corrected() / "castle.yaml", root / "castle.yaml.away");
  const std::string missing = errorOf([&] { runSfmStage(survey, options); });
  EXPECT_NE(missing.find("castle.yaml"), std::string::npos) << missing;
  EXPECT_NE(missing.find("auv recon correct"), std::string::npos) << missing;
  fs::rename(root / "castle.yaml.away", survey.corrected() / "castle.yaml");
  SfmStageOptions strict = options;
  strict.mapper.init_min_inliers = 100000;
  const std::string no_pair = errorOf([&] { runSfmStage(survey, strict); });
  EXPECT_NE(no_pair.find("no initial pair"), std::string::npos) << no_pair;
  EXPECT_EQ(fs::last_write_time(survey.sparse() / "images.txt"), before);
  EXPECT_EQ(scene::readColmapText(survey.sparse()).images.size(), summary.images_registered);

  // A partial result: only the initial pair registers. Its model is written to sparse-partial/
  // and flagged, sparse/ stays; each image left out says why.
  SfmStageOptions picky = options;
  picky.mapper.abs_pose_min_inliers = 100000;
  std::string partial;
  try {
    runSfmStage(survey, picky);
  } catch (const PartialResult& e) {
    partial = e.what();
  }
  EXPECT_NE(partial.find("partial result: 2 of 11 images registered"), std::string::npos)
      << partial;
  EXPECT_NE(partial.find("a resection needs >= 100000"), std::string::npos) << partial;
  EXPECT_NE(partial.find("--accept-partial"), std::string::npos) << partial;
  EXPECT_EQ(scene::readColmapText(root / "sparse-partial").images.size(), 2u);
  EXPECT_EQ(fs::last_write_time(survey.sparse() / "images.txt"), before);
  nlohmann::json sfm = readReport(survey.report())["stages"]["sfm"];
  EXPECT_TRUE(sfm["partial"].get<bool>());
  EXPECT_EQ(sfm["unregistered_reasons"].size(), 9u);
  // Accepted: it becomes sparse/, with a warning.
  picky.accept_partial = true;
  const SfmStageResult accepted = runSfmStage(survey, picky);
  EXPECT_TRUE(accepted.partial);
  ASSERT_FALSE(accepted.warnings.empty());
  EXPECT_NE(accepted.warnings.back().find("accepted"), std::string::npos);
  EXPECT_EQ(scene::readColmapText(survey.sparse()).images.size(), 2u);

  // Uncalibrated: only the EXIF prior (35 mm equivalent: 2865.6 px at full size, -1.4 %).
  // Focal and radial distortion are self-calibrated, and the pinhole workspace is written for
  // dense and texture. Full-size figures (+2.9 % focal, k1 -0.25) in import/README.md.
  writeCorrectedYaml(survey.corrected() / "castle.yaml", 1416, 1064, 2865.58 / 2, 707.75, 531.75,
                     "exif_35mm");
  const SfmStageResult self = runSfmStage(survey, options);
  EXPECT_EQ(self.images_registered, 11u);
  EXPECT_LT(self.mean_reprojection_error_px, 1.0);
  const scene::Reconstruction lens = scene::readColmapText(survey.sparse());
  const scene::Camera& castle = lens.cameras.at(1);
  EXPECT_EQ(castle.model, scene::CameraModel::OPENCV);
  EXPECT_NEAR(castle.fx / (2905.88 / 2), 1.0, 0.04);
  ASSERT_EQ(castle.distortion.size(), 4u);
  EXPECT_LT(castle.distortion[0], -0.1);  // the Kodak's barrel distortion
  const scene::Reconstruction pinhole = scene::readColmapText(survey.undistorted() / "sparse");
  EXPECT_EQ(pinhole.cameras.at(1).model, scene::CameraModel::PINHOLE);
  EXPECT_EQ(pinhole.images.size(), 11u);
  EXPECT_EQ(survey.pinholeWorkspace().images, survey.undistorted());
  for (const auto& [id, image] : pinhole.images) {
    EXPECT_TRUE(fs::exists(survey.undistorted() / image.name)) << image.name;
  }
  // Calibrated again: no distortion, the workspace goes.
  writeCorrectedYaml(survey.corrected() / "castle.yaml", 1416, 1064, 2905.88 / 2, 707.75, 531.75);
  runSfmStage(survey, options);
  EXPECT_FALSE(fs::exists(survey.undistorted()));
  EXPECT_EQ(survey.pinholeWorkspace().model, survey.sparse());
  fs::remove_all(root);
}

TEST(SfmStage, EmptyOrIncompleteSurveysGiveClearErrors) {
  const fs::path root = freshFolder("bad");
  const Survey survey(root);
  // No corrected/ at all.
  std::string error = errorOf([&] { runSfmStage(survey, {}); });
  EXPECT_NE(error.find("corrected"), std::string::npos) << error;
  // A camera folder, no calibration.
  fs::create_directories(survey.corrected() / "left");
  error = errorOf([&] { runSfmStage(survey, {}); });
  EXPECT_NE(error.find("left.yaml"), std::string::npos) << error;
  // Calibration with distortion: SfM wants the undistorted intrinsics.
  {
    cv::FileStorage storage((survey.corrected() / "left.yaml").string(), cv::FileStorage::WRITE);
    storage << "image_width" << 640 << "image_height" << 480;
    storage << "camera_matrix" << (cv::Mat_<double>(3, 3) << 500, 0, 320, 0, 500, 240, 0, 0, 1);
    storage << "distortion_coefficients" << (cv::Mat_<double>(1, 5) << 0.1, 0, 0, 0, 0);
  }
  error = errorOf([&] { runSfmStage(survey, {}); });
  EXPECT_NE(error.find("distortion_coefficients"), std::string::npos) << error;
  writeCorrectedYaml(survey.corrected() / "left.yaml", 640, 480, 500, 320, 240);
  // No features yet.
  error = errorOf([&] { runSfmStage(survey, {}); });
  EXPECT_NE(error.find("features"), std::string::npos) << error;
  EXPECT_FALSE(fs::exists(survey.sparse()));
  fs::remove_all(root);

  SfmStageOptions bad;
  bad.loss = "l3";
  EXPECT_THROW(bad.check(), std::invalid_argument);
  bad = {};
  bad.min_registered_ratio = 1.5;
  EXPECT_THROW(bad.check(), OptionError);
}

TEST(Navigation, ScalesAndTurnsTheModelIntoTheNavigationFrame) {
  const fs::path root = freshFolder("nav");
  // Trajectory: 1 m/s along x, then y; keyframes at t = 0..5.
  {
    std::ofstream tum(root / "navigation.tum");
    tum << "# t x y z qx qy qz qw\n";
    for (int i = 0; i <= 10; ++i) {
      const double t = i * 0.5;
      tum << t << " " << std::min(t, 3.0) << " " << std::max(t - 3.0, 0.0) << " " << 0.1 * t
          << " 0 0 0 1\n";
    }
  }
  const std::vector<TimedPosition> trajectory = readTumTrajectory(root / "navigation.tum");
  ASSERT_EQ(trajectory.size(), 11u);
  Eigen::Vector3d p;
  ASSERT_TRUE(positionAt(trajectory, 1.25, p));
  EXPECT_LT((p - Eigen::Vector3d(1.25, 0, 0.125)).norm(), 1e-12);
  EXPECT_FALSE(positionAt(trajectory, 6.0, p));

  fs::create_directories(root / "keyframes" / "left");
  {
    std::ofstream index(root / "keyframes" / "left" / "index.csv");
    index << "file,video,frame,camera_time_s,sim_time_s,sharpness,motion_px,tracked\n";
    for (int i = 0; i <= 5; ++i) {
      index << "left_0001_" << i << ".png,left_0001.mp4," << i * 10 << "," << i << "," << i
            << ",100,40,200\n";
    }
    index << "left_0001_9.png,left_0001.mp4,90,9,,100,40,200\n";  // unknown time
  }
  const auto times = readKeyframeTimes(root / "keyframes", {"left", "right"});
  EXPECT_EQ(times.size(), 6u);
  EXPECT_EQ(times.at("left/left_0001_3.png"), 3.0);

  // A model at 1/4 scale, rotated and shifted: aligned back to metres.
  scene::Reconstruction rec;
  rec.cameras[1] = scene::Camera::pinhole(1, 640, 480, 500, 500, 320, 240);
  Similarity away;
  away.scale = 0.25;
  away.rotation = Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  away.translation = Eigen::Vector3d(5, 6, 7);
  for (int i = 0; i <= 5; ++i) {
    scene::Image image;
    image.id = i + 1;
    image.camera_id = 1;
    image.name = "left/left_0001_" + std::to_string(i) + ".png";
    Eigen::Vector3d truth;
    positionAt(trajectory, i, truth);
    const Eigen::Vector3d c = away.apply(truth);
    image.t_cw = -(image.q_cw * c);
    rec.images[image.id] = image;
  }
  const NavigationAlignment a = alignToNavigation(rec, times, trajectory);
  ASSERT_TRUE(a.applied) << a.reason;
  EXPECT_EQ(a.images, 6u);
  EXPECT_NEAR(a.similarity.scale, 4.0, 1e-9);
  EXPECT_LT(a.rms_m, 1e-9);
  for (const auto& [id, image] : rec.images) {
    Eigen::Vector3d truth;
    positionAt(trajectory, id - 1, truth);
    EXPECT_LT((image.center() - truth).norm(), 1e-9);
  }
  // Too few timed images: not applied, says why.
  const NavigationAlignment none = alignToNavigation(rec, {}, trajectory);
  EXPECT_FALSE(none.applied);
  EXPECT_NE(none.reason.find("0 registered images"), std::string::npos) << none.reason;
  // Malformed trajectory: names the file and line.
  {
    std::ofstream tum(root / "bad.tum");
    tum << "0 0 0 0 0 0 0 1\n1 2 three\n";
  }
  try {
    readTumTrajectory(root / "bad.tum");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.tum:2"), std::string::npos) << e.what();
  }
  fs::remove_all(root);
}

}  // namespace
}  // namespace auv::recon::sfm
