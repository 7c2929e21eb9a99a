// The static-overlay detector on real videos nobody here made, Debian opencv-doc's sample clips:
// `Megamind.avi`, a film trailer, mostly dark, with cuts and motion everywhere, with a depth and
// time read-out and a housing edge burned in, dark on dark as they often are on underwater
// footage; `vtest.avi`, a fixed street camera with people walking: most of its pixels are still
// and sharp, just like an overlay's, and the detector must refuse it, not mask the street.

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "auv/recon/overlay/overlay_detector.h"

namespace fs = std::filesystem;
using namespace auv::recon;

namespace {

const fs::path kSamples = "/usr/share/doc/opencv-doc/examples/data";

const cv::Rect kReadout(12, 12, 260, 34);
std::vector<cv::Point> housingEdge(cv::Size frame) {
  return {{0, frame.height - 1}, {0, frame.height - 60}, {120, frame.height - 1}};
}

// The read-out's digits change every frame, as a depth gauge's do.
void drawOverlay(cv::Mat& frame, int i) {
  frame(kReadout).setTo(cv::Scalar(20, 20, 20));
  char text[64];
  std::snprintf(text, sizeof text, "D %5.1f m  10:41:%02d", 12.0 + 0.1 * (i % 37), i / 10 % 60);
  cv::putText(frame, text, {kReadout.x + 6, kReadout.y + 24}, cv::FONT_HERSHEY_SIMPLEX, 0.65,
              cv::Scalar(240, 240, 240), 1, cv::LINE_AA);
  cv::fillPoly(frame, std::vector<std::vector<cv::Point>>{housingEdge(frame.size())},
               cv::Scalar(40, 45, 50), cv::LINE_AA);
}

}  // namespace

TEST(OverlayRealVideo, FindsADarkReadoutAndHousingBurnedIntoADarkTrailer) {
  const fs::path clip_file = kSamples / "Megamind.avi";
  if (!fs::exists(clip_file)) {
    GTEST_SKIP() << clip_file << " absent: install opencv-doc (scripts/install-deps.sh)";
  }
  const fs::path video =
      fs::temp_directory_path() / ("auv_overlay_trailer_" + std::to_string(::getpid()) + ".avi");
  cv::VideoCapture clip(clip_file.string());
  ASSERT_TRUE(clip.isOpened());
  cv::VideoWriter writer;
  cv::Mat frame;
  int frames = 0;
  while (clip.read(frame)) {
    if (!writer.isOpened()) {
      writer.open(video.string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 24, frame.size());
      ASSERT_TRUE(writer.isOpened());
    }
    drawOverlay(frame, frames++);
    writer.write(frame);
  }
  writer.release();
  ASSERT_GT(frames, 100) << "the sample clip decoded to too few frames";

  // With the default margin, as a user runs it: what matters for matching is that the
  // overlay's pixels are all masked and little of the scene beyond the margin is.
  const overlay::OverlayOptions options;
  const overlay::OverlayDetection detection = overlay::detectInVideos({video}, options);
  fs::remove(video);
  const cv::Size size = detection.mask.size();
  cv::Mat truth = cv::Mat::zeros(size, CV_8U);
  truth(kReadout).setTo(255);
  cv::fillPoly(truth, std::vector<std::vector<cv::Point>>{housingEdge(size)}, cv::Scalar(255));
  const cv::Mat found = detection.mask == 0;
  const double covered =
      static_cast<double>(cv::countNonZero(found & truth)) / cv::countNonZero(truth);
  const int reach = 2 * (options.dilate_px + 4) + 1;
  cv::Mat near;
  cv::dilate(truth, near, cv::getStructuringElement(cv::MORPH_ELLIPSE, {reach, reach}));
  const double scene_flagged =
      static_cast<double>(cv::countNonZero(found & (near == 0))) / cv::countNonZero(near == 0);
  std::cout << frames << " frames; overlay covered " << 100 * covered << " %, scene flagged "
            << 100 * scene_flagged << " %, regions " << detection.regions << std::endl;
  EXPECT_GT(covered, 0.97);
  EXPECT_LT(scene_flagged, 0.01);
}

TEST(OverlayRealVideo, AFixedSurveillanceCameraIsRefusedNotMaskedWholesale) {
  const fs::path video = kSamples / "vtest.avi";
  if (!fs::exists(video)) {
    GTEST_SKIP() << video << " absent: install opencv-doc (scripts/install-deps.sh)";
  }
  try {
    const overlay::OverlayDetection detection =
        overlay::detectInVideos({video}, overlay::OverlayOptions());
    FAIL() << "a fixed camera gave a mask hiding " << 100 * detection.masked_fraction
           << " % of the image (moving " << detection.moving_fraction << ")";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("barely moves"), std::string::npos) << e.what();
  }
}
