// The static-overlay detector (overlay/overlay_detector.h) and `auv recon masks`
// (overlay/masks_stage.h) on a video panning over a real photo (Sceaux castle) with a burned-in
// timestamp box and a vehicle part in a corner drawn on every frame.

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "auv/recon/common/stage_error.h"
#include "auv/recon/masks/mask.h"
#include "auv/recon/overlay/masks_stage.h"
#include "auv/recon/overlay/overlay_detector.h"

namespace fs = std::filesystem;
using namespace auv::recon;

namespace {

const cv::Size kFrame(480, 360);
const cv::Rect kBox(10, 10, 230, 30);  // the timestamp's box

// The vehicle's part: a polygon in the bottom-right corner, touching the image border.
std::vector<cv::Point> vehiclePart() { return {{400, 359}, {430, 300}, {479, 280}, {479, 359}}; }

// The true overlay pixels (255).
cv::Mat trueOverlay() {
  cv::Mat truth = cv::Mat::zeros(kFrame, CV_8U);
  truth(kBox).setTo(255);
  cv::fillPoly(truth, std::vector<std::vector<cv::Point>>{vehiclePart()}, cv::Scalar(255));
  return truth;
}

// Draws the overlay of frame `i` (the seconds of the timestamp change every 10 frames).
void drawOverlay(cv::Mat& frame, int i) {
  frame(kBox).setTo(cv::Scalar(25, 25, 25));
  char text[64];
  std::snprintf(text, sizeof text, "2026-11-27 10:41:%02d", i / 10);
  cv::putText(frame, text, {kBox.x + 6, kBox.y + 22}, cv::FONT_HERSHEY_SIMPLEX, 0.6,
              cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  cv::fillPoly(frame, std::vector<std::vector<cv::Point>>{vehiclePart()}, cv::Scalar(70, 90, 110),
               cv::LINE_AA);
}

class OverlayTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const fs::path photo =
        fs::path(AUV_RECON_SHARED_DATA) / "sceaux_castle" / "images" / "100_7100.JPG";
    scene_ = cv::imread(photo.string(), cv::IMREAD_COLOR);
    if (scene_.empty()) GTEST_SKIP() << "no " << photo << " (shared data absent)";
    cv::resize(scene_, scene_, {1416, 1064}, 0, 0, cv::INTER_AREA);
    root_ = fs::temp_directory_path() /
            ("auv_overlay_" +
             std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
             std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  void TearDown() override {
    if (!root_.empty()) fs::remove_all(root_);
  }

  // A video panning over the photo (`pan` = false: a still camera), with the overlay.
  fs::path writeVideo(const fs::path& file, int frames, bool pan) {
    fs::create_directories(file.parent_path());
    cv::VideoWriter writer(file.string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10, kFrame);
    EXPECT_TRUE(writer.isOpened());
    for (int i = 0; i < frames; ++i) {
      const double t = pan ? static_cast<double>(i) / (frames - 1) : 0.0;
      const int x = static_cast<int>(t * (scene_.cols - kFrame.width));
      const int y =
          static_cast<int>((0.5 - 0.5 * std::cos(6.28 * t)) * (scene_.rows - kFrame.height) * 0.8);
      cv::Mat frame = scene_(cv::Rect({x, y}, kFrame)).clone();
      drawOverlay(frame, i);
      writer.write(frame);
    }
    return file;
  }

  cv::Mat scene_;
  fs::path root_;
};

TEST_F(OverlayTest, FindsTheBurnedInOverlayAndLittleOfTheScene) {
  const fs::path video = writeVideo(root_ / "v.avi", 80, true);
  overlay::OverlayOptions options;
  options.dilate_px = 0;  // compared with the exact overlay
  const overlay::OverlayDetection detection = overlay::detectInVideos({video}, options);
  ASSERT_EQ(detection.mask.size(), kFrame);
  EXPECT_EQ(detection.frames, options.samples);
  const cv::Mat found = detection.mask == 0;
  const cv::Mat truth = trueOverlay();
  const double intersection = cv::countNonZero(found & truth);
  const double iou = intersection / cv::countNonZero(found | truth);
  // False positives: found pixels of the scene, away from the overlay's outline.
  cv::Mat near;
  cv::dilate(truth, near, cv::getStructuringElement(cv::MORPH_ELLIPSE, {9, 9}));
  const double scene_pixels = cv::countNonZero(near == 0);
  const double false_positive = cv::countNonZero(found & (near == 0)) / scene_pixels;
  std::cout << "overlay IoU " << iou << ", scene pixels flagged " << 100 * false_positive
            << " %, regions " << detection.regions << ", moving " << detection.moving_fraction
            << std::endl;
  EXPECT_GT(iou, 0.85);
  EXPECT_LT(false_positive, 0.005);
  EXPECT_EQ(detection.regions, 2);
}

TEST_F(OverlayTest, AStillCameraIsRefusedSayingWhy) {
  const fs::path video = writeVideo(root_ / "still.avi", 30, false);
  try {
    overlay::detectInVideos({video}, overlay::OverlayOptions());
    FAIL() << "a still scene gave a mask";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("barely moves"), std::string::npos) << e.what();
  }
}

TEST_F(OverlayTest, MasksStageWritesTheCameraMaskAndNeverOverwritesOne) {
  const Survey survey(root_);
  writeVideo(survey.recordings() / "cam" / "cam_0001.avi", 60, true);
  overlay::MasksStageOptions options;
  options.detect_overlay = true;
  const auto result = overlay::runMasksStage(survey, options);
  ASSERT_EQ(result.cameras.size(), 1u);
  EXPECT_TRUE(result.cameras[0].detected);
  const fs::path file = masks::cameraMaskFile(survey, "cam");
  const cv::Mat written = masks::loadMask(file, kFrame, "test");
  EXPECT_GT(cv::countNonZero(written(kBox) == 0), 0.95 * kBox.area());
  EXPECT_EQ(written.at<uint8_t>(180, 240), 255);  // the scene in the middle is kept

  // A user's mask (here: edited) is never replaced without --replace.
  cv::Mat edited(kFrame, CV_8U, cv::Scalar(255));
  ASSERT_TRUE(cv::imwrite(file.string(), edited));
  try {
    overlay::runMasksStage(survey, options);
    FAIL() << "an existing mask was overwritten";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("--replace"), std::string::npos) << e.what();
  }
  EXPECT_EQ(cv::countNonZero(masks::loadMask(file, kFrame, "test") == 0), 0);
  options.replace = true;
  overlay::runMasksStage(survey, options);
  EXPECT_GT(cv::countNonZero(masks::loadMask(file, kFrame, "test") == 0), kBox.area());

  // Checking only (no detection): a keyframe whose mask has another size is named.
  fs::create_directories(survey.keyframes() / "cam");
  cv::imwrite((survey.keyframes() / "cam" / "k.png").string(), cv::Mat(100, 80, CV_8UC3));
  options.detect_overlay = false;
  try {
    overlay::runMasksStage(survey, options);
    FAIL() << "a wrong-size mask passed the check";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("80x100"), std::string::npos) << e.what();
  }
}

}  // namespace

TEST(OverlayOptions, BadValuesAreRefusedNamingTheField) {
  const std::vector<std::pair<std::string, void (*)(overlay::OverlayOptions&)>> cases = {
      {"samples", [](overlay::OverlayOptions& o) { o.samples = 1; }},
      {"max_std", [](overlay::OverlayOptions& o) { o.max_std = 0; }},
      {"min_gradient", [](overlay::OverlayOptions& o) { o.min_gradient = 0; }},
      {"max_std_flat", [](overlay::OverlayOptions& o) { o.max_std_flat = -1; }},
      {"max_std_flat", [](overlay::OverlayOptions& o) { o.max_std_flat = o.max_std; }},
      {"close_px", [](overlay::OverlayOptions& o) { o.close_px = -1; }},
      {"min_moving_fraction", [](overlay::OverlayOptions& o) { o.min_moving_fraction = 2; }},
  };
  for (const auto& [field, spoil] : cases) {
    overlay::OverlayOptions options;
    spoil(options);
    try {
      options.check();
      ADD_FAILURE() << field << ": a bad value was accepted";
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  }
  EXPECT_NO_THROW(overlay::OverlayOptions().check());
}
