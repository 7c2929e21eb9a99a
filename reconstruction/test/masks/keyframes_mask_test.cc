// Keyframe selection with a camera mask (keyframes/selector.h setMask): a large static burned-in
// panel holds the median motion at zero and its corners stay "tracked", so without the mask a
// panning camera gives no new keyframe; with it, the scene's motion triggers them.

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "auv/recon/keyframes/selector.h"

using namespace auv::recon::keyframes;

namespace {

cv::Mat texture(cv::Size size, int seed) {
  cv::RNG rng(seed);
  cv::Mat noise(size.height / 4, size.width / 4, CV_8U), image;
  rng.fill(noise, cv::RNG::UNIFORM, 0, 255);
  cv::resize(noise, image, size, 0, 0, cv::INTER_CUBIC);
  cv::GaussianBlur(image, image, {0, 0}, 1.0);
  return image;
}

int keyframesOfPan(bool masked) {
  const cv::Size frame_size(320, 240);
  const cv::Mat scene = texture({1000, 240}, 1);
  const cv::Mat panel = texture({192, 240}, 2);  // burned in over the left 60 % of the frame
  KeyframeOptions options;
  options.analysis_width = 0;
  KeyframeSelector selector(options);
  if (masked) {
    cv::Mat mask(frame_size, CV_8U, cv::Scalar(255));
    mask(cv::Rect(0, 0, 192, 240)).setTo(0);
    selector.setMask(mask);
  }
  int keyframes = 0;
  for (int i = 0; i < 150; ++i) {
    cv::Mat frame = scene(cv::Rect(4 * i, 0, 320, 240)).clone();
    panel.copyTo(frame(cv::Rect(0, 0, 192, 240)));
    keyframes += selector.addFrame(i, frame) ? 1 : 0;
  }
  keyframes += selector.finish() ? 1 : 0;
  return keyframes;
}

TEST(KeyframesMask, AStaticOverlayNoLongerHidesTheMotion) {
  const int without = keyframesOfPan(false);
  const int with = keyframesOfPan(true);
  std::cout << "keyframes of a 600 px pan: " << without << " without the mask, " << with
            << " with it" << std::endl;
  EXPECT_LE(without, 1);
  EXPECT_GE(with, 5);
}

TEST(KeyframesMask, AMaskOfAnotherSizeIsRefused) {
  KeyframeSelector selector{KeyframeOptions()};
  selector.setMask(cv::Mat(100, 100, CV_8U, cv::Scalar(255)));
  EXPECT_THROW(selector.addFrame(0, cv::Mat(240, 320, CV_8U, cv::Scalar(0))),
               std::invalid_argument);
}

}  // namespace
