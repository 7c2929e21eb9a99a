// Masks (masks/mask.h): which file masks an image, the size check, keypoints kept off masked
// pixels by the features stage, masks remapped for undistorted images.

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "auv/recon/calibration/calibration.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/features/feature_store.h"
#include "auv/recon/features/features_stage.h"
#include "auv/recon/features/sift_extractor.h"
#include "auv/recon/masks/mask.h"
#include "auv/recon/scene/colmap_text.h"
#include "auv/recon/sfm/undistorted_model.h"

namespace fs = std::filesystem;
using namespace auv::recon;

namespace {

class MaskTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() /
            ("auv_masks_" +
             std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
             std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  void TearDown() override { fs::remove_all(root_); }

  static void writeMask(const fs::path& file, cv::Size size, cv::Rect ignored) {
    fs::create_directories(file.parent_path());
    cv::Mat mask(size, CV_8U, cv::Scalar(255));
    mask(ignored).setTo(0);
    ASSERT_TRUE(cv::imwrite(file.string(), mask));
  }

  // A textured image SIFT finds many keypoints in everywhere: blurred noise at two scales.
  static cv::Mat texturedImage(cv::Size size, int seed) {
    cv::RNG rng(seed);
    cv::Mat coarse(size.height / 8, size.width / 8, CV_8U), fine(size, CV_8U), image;
    rng.fill(coarse, cv::RNG::UNIFORM, 0, 255);
    rng.fill(fine, cv::RNG::UNIFORM, 0, 255);
    cv::resize(coarse, coarse, size, 0, 0, cv::INTER_CUBIC);
    cv::GaussianBlur(fine, fine, {0, 0}, 2.0);
    cv::addWeighted(coarse, 0.6, fine, 0.4, 0, image);
    cv::cvtColor(image, image, cv::COLOR_GRAY2BGR);
    return image;
  }

  fs::path root_;
};

TEST_F(MaskTest, PerImageMaskWinsOverTheCameraMask) {
  const Survey survey(root_);
  EXPECT_EQ(masks::findMask(survey, "left", "left_000010.png"), std::nullopt);
  writeMask(root_ / "masks" / "left.png", {64, 48}, {0, 0, 8, 8});
  writeMask(root_ / "masks" / "left" / "left_000010.png.png", {64, 48}, {0, 0, 16, 16});
  EXPECT_EQ(masks::findMask(survey, "left", "left_000010.png"),
            root_ / "masks" / "left" / "left_000010.png.png");
  EXPECT_EQ(masks::findMask(survey, "left", "left_000020.png"), root_ / "masks" / "left.png");
  EXPECT_EQ(masks::findMask(survey, "right", "left_000010.png"), std::nullopt);
  // COLMAP's name: the image's whole file name + ".png", not its stem.
  writeMask(root_ / "masks" / "right" / "a.png", {64, 48}, {0, 0, 16, 16});
  EXPECT_EQ(masks::findMask(survey, "right", "a.png"), std::nullopt);

  const masks::CameraMasks left(survey, "left", "test");
  ASSERT_TRUE(left.any());
  EXPECT_FALSE(left.remapped());
  const cv::Mat own = left.forImage("left_000010.png", {64, 48});
  const cv::Mat shared = left.forImage("left_000020.png", {64, 48});
  EXPECT_EQ(cv::countNonZero(own == 0), 16 * 16);
  EXPECT_EQ(cv::countNonZero(shared == 0), 8 * 8);
  EXPECT_TRUE(masks::CameraMasks(survey, "right", "test").forImage("b.png", {64, 48}).empty());
  EXPECT_TRUE(masks::CameraMasks(survey, "none", "test").forImage("b.png", {64, 48}).empty());
}

TEST_F(MaskTest, WrongSizeMaskIsAnErrorNamingTheFileAndBothSizes) {
  const fs::path file = root_ / "masks" / "left.png";
  writeMask(file, {100, 50}, {0, 0, 10, 10});
  try {
    masks::loadMask(file, {200, 100}, "features", "image left/a.png");
    FAIL() << "a mask of the wrong size was accepted";
  } catch (const StageError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(file.string()), std::string::npos) << message;
    EXPECT_NE(message.find("100x50"), std::string::npos) << message;
    EXPECT_NE(message.find("200x100"), std::string::npos) << message;
    EXPECT_NE(message.find("left/a.png"), std::string::npos) << message;
  }
  // Binary 0/255 whatever the grey levels; unreadable masks are named.
  cv::Mat grey(10, 10, CV_8U, cv::Scalar(7));
  grey(cv::Rect(0, 0, 5, 10)).setTo(0);
  ASSERT_TRUE(cv::imwrite((root_ / "grey.png").string(), grey));
  const cv::Mat loaded = masks::loadMask(root_ / "grey.png", {10, 10}, "test");
  EXPECT_EQ(cv::countNonZero(loaded == 255), 50);
  EXPECT_EQ(cv::countNonZero(loaded == 0), 50);
  std::ofstream(root_ / "broken.png") << "not a png";
  EXPECT_THROW(masks::loadMask(root_ / "broken.png", {10, 10}, "test"), StageError);
}

TEST_F(MaskTest, SiftKeepsNoKeypointOnMaskedPixels) {
  const cv::Mat image = texturedImage({640, 480}, 1);
  features::SiftOptions options;
  const auto all = features::extractSift(image, "a", options);
  cv::Mat mask(image.size(), CV_8U, cv::Scalar(255));
  const cv::Rect ignored(0, 0, 320, 200);
  mask(ignored).setTo(0);
  const auto masked = features::extractSift(image, "a", options, mask);
  size_t inside_all = 0;
  for (const auto& k : all.keypoints) inside_all += ignored.contains({int(k.x), int(k.y)});
  ASSERT_GT(inside_all, 50u) << "the test image has keypoints in the region";
  ASSERT_GT(masked.keypoints.size(), 100u);
  for (const auto& k : masked.keypoints) {
    const int u = static_cast<int>(std::lround(k.x)), v = static_cast<int>(std::lround(k.y));
    EXPECT_FALSE(ignored.contains({u, v})) << k.x << "," << k.y;
  }
  // The cap applies after the mask: a masked image keeps as many keypoints as allowed.
  options.max_features = 300;
  EXPECT_EQ(features::extractSift(image, "a", options, mask).keypoints.size(), 300u);
  // Downscaled detection: the mask follows the scale.
  options.max_features = 0;
  options.max_image_size = 320;
  for (const auto& k : features::extractSift(image, "a", options, mask).keypoints) {
    EXPECT_FALSE(cv::Rect(2, 2, 316, 196).contains({int(k.x), int(k.y)})) << k.x << "," << k.y;
  }
}

TEST_F(MaskTest, FeaturesStageHonoursMasksAndRefusesAWrongSizeOne) {
  const Survey survey(root_);
  fs::create_directories(survey.corrected() / "cam");
  for (int i = 0; i < 2; ++i) {
    cv::imwrite((survey.corrected() / "cam" / ("f" + std::to_string(i) + ".png")).string(),
                texturedImage({320, 240}, 10 + i));
  }
  const cv::Rect ignored(0, 0, 160, 240);
  writeMask(masks::cameraMaskFile(survey, "cam"), {320, 240}, ignored);
  features::FeaturesStageOptions options;
  options.threads = 1;
  const auto result = features::runFeaturesStage(survey, options);
  EXPECT_EQ(result.masked_images, 2u);
  features::FeatureStore store(survey.root() / "features");
  for (const char* name : {"cam/f0.png", "cam/f1.png"}) {
    const auto f = store.read(name);
    ASSERT_GT(f.keypoints.size(), 20u);
    for (const auto& k : f.keypoints) EXPECT_GE(std::lround(k.x), 160) << name;
  }
  // A mask of another resolution: the stage fails naming it; the features stay as they were.
  writeMask(masks::imageMaskFile(survey, "cam", "f1.png"), {640, 480}, ignored);
  const auto before = fs::last_write_time(survey.root() / "features" / "index.csv");
  try {
    features::runFeaturesStage(survey, options);
    FAIL() << "a wrong-size mask was accepted";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find(masks::imageMaskFile(survey, "cam", "f1.png").string()),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(fs::last_write_time(survey.root() / "features" / "index.csv"), before);
}

TEST_F(MaskTest, MasksOfUndistortedImagesAreRemappedLikeTheImages) {
  const Survey survey(root_);
  const cv::Size size(320, 240);
  calibration::CameraCalibration original;
  original.image_size = size;
  original.camera_matrix = (cv::Mat_<double>(3, 3) << 300, 0, 160, 0, 300, 120, 0, 0, 1);
  original.distortion = (cv::Mat_<double>(1, 5) << -0.3, 0.1, 0, 0, 0);
  calibration::CameraCalibration corrected = original.clone();
  corrected.camera_matrix = (cv::Mat_<double>(3, 3) << 250, 0, 158, 0, 250, 121, 0, 0, 1);
  corrected.distortion = cv::Mat::zeros(1, 5, CV_64F);
  const calibration::CalibrationOptions board;
  fs::create_directories(survey.calibration());
  fs::create_directories(survey.corrected());
  calibration::writeCalibration(survey.calibrationFile("cam"), original, board);
  calibration::writeCalibration(survey.corrected() / "cam.yaml", corrected, board);
  // A 20x20 box near a corner, where the distortion moves pixels most.
  const cv::Rect box(20, 20, 20, 20);
  writeMask(masks::cameraMaskFile(survey, "cam"), size, box);
  const masks::CameraMasks masks(survey, "cam", "test");
  ASSERT_TRUE(masks.remapped());
  const cv::Mat mask = masks.forImage("a.png", size);
  ASSERT_EQ(mask.size(), size);
  // Where the box's centre lands in the undistorted image.
  std::vector<cv::Point2f> centre{{29.5f, 29.5f}}, moved;
  cv::undistortPoints(centre, moved, original.camera_matrix, original.distortion, cv::noArray(),
                      corrected.camera_matrix);
  const cv::Point p(static_cast<int>(std::lround(moved[0].x)),
                    static_cast<int>(std::lround(moved[0].y)));
  ASSERT_GT(cv::norm(moved[0] - centre[0]), 3.0) << "the distortion must move the box";
  EXPECT_EQ(mask.at<uint8_t>(p), 0) << "box centre at " << p;
  EXPECT_EQ(mask.at<uint8_t>(120, 160), 255);
  // Still binary (nearest neighbour).
  EXPECT_EQ(cv::countNonZero(mask == 0) + cv::countNonZero(mask == 255),
            static_cast<int>(mask.total()));
}

TEST_F(MaskTest, MasksFollowTheSelfCalibratedLensIntoUndistorted) {
  // No calibration: corrected/ has the raw geometry and sfm self-calibrated a barrel lens; dense
  // and texture read undistorted/, so a mask must move with the lens as its image did.
  const Survey survey(root_);
  const cv::Size size(320, 240);
  scene::Reconstruction model;
  scene::Camera lens = scene::Camera::pinhole(1, size.width, size.height, 300, 300, 160, 120);
  lens.model = scene::CameraModel::OPENCV;
  lens.distortion = {-0.3, 0.1, 0, 0};
  model.cameras[1] = lens;
  scene::Image image;
  image.id = 1;
  image.camera_id = 1;
  image.name = "cam/a.png";
  model.images[1] = image;
  fs::create_directories(survey.sparse());
  scene::writeColmapText(model, survey.sparse());
  fs::create_directories(survey.corrected() / "cam");
  ASSERT_TRUE(cv::imwrite((survey.corrected() / "cam" / "a.png").string(), texturedImage(size, 3)));
  sfm::writeUndistortedWorkspace(model, survey.corrected(), survey.undistorted());
  ASSERT_EQ(survey.pinholeWorkspace().images, survey.undistorted());
  const cv::Rect box(16, 16, 8, 8);  // near a corner, where the lens moves pixels most
  writeMask(masks::cameraMaskFile(survey, "cam"), size, box);

  const masks::SurveyMasks masks(survey, "test");
  const cv::Mat mask = masks.forImage("cam/a.png", size);
  ASSERT_EQ(mask.size(), size);
  // Where the box's centre lands in the undistorted image (the pinhole of undistorted/sparse).
  const scene::Reconstruction pinhole = scene::readColmapText(survey.undistorted() / "sparse");
  const scene::Camera& undistorted = pinhole.cameras.at(1);
  const Eigen::Vector2d n = lens.pixelToNormalized({19.5, 19.5});
  const cv::Point p(static_cast<int>(std::lround(undistorted.fx * n.x() + undistorted.cx)),
                    static_cast<int>(std::lround(undistorted.fy * n.y() + undistorted.cy)));
  ASSERT_GT(std::max(std::abs(p.x - 19), std::abs(p.y - 19)), 5) << "the lens must move the box";
  EXPECT_EQ(mask.at<uint8_t>(p), 0) << "box centre at " << p;
  EXPECT_EQ(mask.at<uint8_t>(19, 19), 255) << "the mask as drawn would be misplaced";
  EXPECT_EQ(mask.at<uint8_t>(120, 160), 255);
  EXPECT_EQ(cv::countNonZero(mask == 0) + cv::countNonZero(mask == 255),
            static_cast<int>(mask.total()));
  // An image of a pinhole camera (none here) or a survey without undistorted/ keeps the mask.
  fs::remove_all(survey.undistorted());
  const masks::SurveyMasks as_drawn(survey, "test");
  EXPECT_EQ(as_drawn.forImage("cam/a.png", size).at<uint8_t>(19, 19), 0);
}

}  // namespace
