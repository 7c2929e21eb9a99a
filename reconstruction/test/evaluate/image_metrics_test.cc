// PSNR with known errors, held-out frame choice, reading frames of a video.
#include "auv/recon/evaluate/image_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "auv/recon/common/stage_error.h"
#include "synthetic_scene.h"

namespace auv::recon::evaluate {
namespace {

cv::Mat texture(int seed) {
  cv::Mat image(120, 160, CV_8UC3);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 30, 220);
  return image;
}

TEST(Psnr, IdenticalImagesAreInfinite) {
  const cv::Mat a = texture(1);
  const PsnrResult r = psnr(a, a.clone());
  EXPECT_TRUE(std::isinf(r.psnr_db));
  EXPECT_EQ(r.mse, 0.0);
  EXPECT_EQ(r.pixels, a.total());
}

TEST(Psnr, KnownErrors) {
  const cv::Mat a = texture(2);
  // A constant error of 5 on every value: MSE 25, PSNR = 10 log10(255^2 / 25) = 34.15 dB; an
  // offset is undone by the gain/offset fit.
  cv::Mat b = a + cv::Scalar(5, 5, 5);
  PsnrResult r = psnr(a, b);
  EXPECT_DOUBLE_EQ(r.mse, 25.0);
  EXPECT_NEAR(r.psnr_db, 10 * std::log10(255.0 * 255.0 / 25.0), 1e-9);
  EXPECT_GT(r.psnr_gain_db, 100.0);
  // Gaussian noise of sigma 10: MSE ~ 100, PSNR ~ 28.13 dB (clipping is rare in [30, 220]).
  cv::Mat noise(a.size(), CV_16SC3);
  cv::RNG rng(4);
  rng.fill(noise, cv::RNG::NORMAL, 0, 10);
  cv::Mat noisy;
  cv::add(a, noise, noisy, cv::noArray(), CV_8UC3);
  r = psnr(a, noisy);
  EXPECT_NEAR(r.mse, 100.0, 5.0);
  EXPECT_NEAR(r.psnr_db, 28.13, 0.25);
  // A gain of 0.5 costs a lot raw, nothing after the fit (up to rounding to 8 bits).
  cv::Mat darker;
  a.convertTo(darker, CV_8UC3, 0.5);
  r = psnr(a, darker);
  EXPECT_LT(r.psnr_db, 20.0);
  EXPECT_GT(r.psnr_gain_db, 45.0);
}

TEST(Psnr, MaskSelectsThePixels) {
  const cv::Mat a = texture(3);
  cv::Mat b = a.clone();
  b(cv::Rect(0, 0, 80, 120)).setTo(cv::Scalar(0, 0, 0));  // left half wrong
  cv::Mat mask = cv::Mat::zeros(a.size(), CV_8U);
  mask(cv::Rect(80, 0, 80, 120)).setTo(255);  // right half compared
  const PsnrResult r = psnr(a, b, mask);
  EXPECT_TRUE(std::isinf(r.psnr_db));
  EXPECT_EQ(r.pixels, 80u * 120u);
  EXPECT_EQ(psnr(a, b, cv::Mat::zeros(a.size(), CV_8U)).pixels, 0u);
}

TEST(Psnr, MismatchedImagesAreErrors) {
  EXPECT_THROW(psnr(texture(1), cv::Mat(10, 10, CV_8UC3)), std::invalid_argument);
  EXPECT_THROW(psnr(texture(1), cv::Mat()), std::invalid_argument);
  EXPECT_THROW(psnr(texture(1), texture(1), cv::Mat(3, 3, CV_8U)), std::invalid_argument);
}

TEST(HeldOutFrames, MiddleOfTheWidestGaps) {
  // Keyframes 0, 10, 14, 40: gaps 10, 4, 26 -> middles 27, 5, 12 in that order of preference.
  EXPECT_EQ(heldOutFrames({40, 0, 10, 14}, 50, 2), (std::vector<int64_t>{5, 27}));
  EXPECT_EQ(heldOutFrames({40, 0, 10, 14}, 50, 10), (std::vector<int64_t>{5, 12, 27}));
  EXPECT_TRUE(heldOutFrames({3, 4}, 10, 5).empty());  // adjacent frames: nothing in between
  EXPECT_TRUE(heldOutFrames({}, 10, 5).empty());
}

TEST(ReadVideoFrames, FramesByNumber) {
  const auto folder = testing::freshFolder("video");
  const auto video = folder / "clip.avi";
  {
    cv::VideoWriter writer(video.string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10,
                           cv::Size(64, 48));
    ASSERT_TRUE(writer.isOpened());
    for (int i = 0; i < 12; ++i) writer.write(cv::Mat(48, 64, CV_8UC3, cv::Scalar::all(i * 20)));
  }
  const std::vector<cv::Mat> frames = readVideoFrames(video, {7, 2, 7});
  ASSERT_EQ(frames.size(), 3u);
  EXPECT_NEAR(cv::mean(frames[0])[0], 140, 4);
  EXPECT_NEAR(cv::mean(frames[1])[0], 40, 4);
  EXPECT_NEAR(cv::mean(frames[2])[0], 140, 4);
  try {
    readVideoFrame(video, 30);
    FAIL() << "frame past the end accepted";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("has 12 frames"), std::string::npos) << e.what();
  }
  EXPECT_THROW(readVideoFrame(folder / "missing.mp4", 0), StageError);
}

}  // namespace
}  // namespace auv::recon::evaluate

// Sharma, Wu and Dalal (2005), "The CIEDE2000 color-difference formula: implementation notes,
// supplementary test data": pairs 1, 7, 17, 25 and 34 of their table (expected to 4 decimals).
TEST(DeltaE, Ciede2000MatchesSharmasTestData) {
  using auv::recon::evaluate::ciede2000;
  EXPECT_NEAR(ciede2000({50.0, 2.6772, -79.7751}, {50.0, 0.0, -82.7485}), 2.0425, 1e-4);
  EXPECT_NEAR(ciede2000({50.0, 0.0, 0.0}, {50.0, -1.0, 2.0}), 2.3669, 1e-4);
  EXPECT_NEAR(ciede2000({50.0, 2.5, 0.0}, {73.0, 25.0, -18.0}), 27.1492, 1e-4);
  EXPECT_NEAR(ciede2000({60.2574, -34.0099, 36.2677}, {60.4626, -34.1751, 39.4387}), 1.2644, 1e-4);
  EXPECT_NEAR(ciede2000({2.0776, 0.0795, -1.1350}, {0.9033, -0.0636, -0.5514}), 0.9082, 1e-4);
  EXPECT_DOUBLE_EQ(ciede2000({40, 10, -5}, {40, 10, -5}), 0.0);
}

TEST(DeltaE, ImagesOverAMask) {
  using auv::recon::evaluate::deltaE2000;
  cv::Mat3b a(10, 10, cv::Vec3b(100, 120, 140)), b = a.clone();
  b(cv::Rect(0, 0, 5, 10)).setTo(cv::Vec3b(100, 120, 200));
  cv::Mat1b left(10, 10, uchar(0)), right(10, 10, uchar(0));
  left(cv::Rect(0, 0, 5, 10)).setTo(255);
  right(cv::Rect(5, 0, 5, 10)).setTo(255);
  EXPECT_NEAR(deltaE2000(a, b, right).mean, 0.0, 1e-6);
  const auto changed = deltaE2000(a, b, left);
  EXPECT_EQ(changed.pixels, 50u);
  EXPECT_GT(changed.mean, 5.0);
  const auto whole = deltaE2000(a, b);  // empty mask: every pixel, half of them changed
  EXPECT_EQ(whole.pixels, 100u);
  EXPECT_NEAR(whole.mean, changed.mean / 2, 1e-9);
  EXPECT_THROW(deltaE2000(a, cv::Mat3b(5, 5)), std::invalid_argument);
}
