// Colour correction (paper section 3.2): the lαβ round trip, a synthetic underwater cast
// (per-channel attenuation + a greenish veil) removed, and the `correct` stage over a survey
// (undistortion, missing calibration, earlier outputs intact).
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "auv/recon/calibration/calibration.h"
#include "auv/recon/color/correct_stage.h"
#include "auv/recon/color/correction.h"
#include "auv/recon/color/lalphabeta.h"
#include "auv/recon/common/option_set.h"
#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"

namespace fs = std::filesystem;
using namespace auv::recon;
using namespace auv::recon::color;

namespace {

fs::path freshFolder(const std::string& name) {
  const fs::path folder =
      fs::temp_directory_path() / ("auv_recon_color_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(folder);
  fs::create_directories(folder);
  return folder;
}

/// A colourful scene whose average is neutral (the grey-world assumption holds): random
/// patches of random hue, each with its complement elsewhere.
cv::Mat neutralScene(int width, int height, unsigned seed) {
  cv::RNG rng(seed);
  cv::Mat image(height, width, CV_8UC3, cv::Scalar(128, 128, 128));
  const int patch = 16;
  for (int y = 0; y < height; y += patch) {
    for (int x = 0; x < width; x += 2 * patch) {
      const int grey = rng.uniform(60, 200);
      const cv::Vec3i offset(rng.uniform(-50, 50), rng.uniform(-50, 50), rng.uniform(-50, 50));
      const cv::Scalar a(grey + offset[0], grey + offset[1], grey + offset[2]);
      const cv::Scalar b(grey - offset[0], grey - offset[1], grey - offset[2]);
      cv::rectangle(image, cv::Rect(x, y, patch, patch), a, cv::FILLED);
      cv::rectangle(image, cv::Rect(x + patch, y, patch, patch), b, cv::FILLED);
    }
  }
  return image;
}

/// Underwater degradation in linear light: red absorbed most, plus a blue-green veil.
cv::Mat underwater(const cv::Mat& scene) {
  const cv::Vec3f transmission(0.85f, 0.7f, 0.25f);  // B, G, R
  const cv::Vec3f veil(0.10f, 0.08f, 0.01f);
  cv::Mat out(scene.size(), CV_8UC3);
  for (int y = 0; y < scene.rows; ++y) {
    for (int x = 0; x < scene.cols; ++x) {
      for (int c = 0; c < 3; ++c) {
        const float linear = srgbToLinear(scene.at<cv::Vec3b>(y, x)[c] / 255.f);
        const float degraded = linear * transmission[c] + veil[c];
        out.at<cv::Vec3b>(y, x)[c] = cv::saturate_cast<uchar>(linearToSrgb(degraded) * 255.f);
      }
    }
  }
  return out;
}

/// Mean angle (degrees) between the linear RGB vectors of two images, pixel by pixel: the
/// colour constancy error, blind to brightness.
double meanAngularError(const cv::Mat& a, const cv::Mat& b) {
  double sum = 0;
  for (int y = 0; y < a.rows; ++y) {
    for (int x = 0; x < a.cols; ++x) {
      cv::Vec3d u, v;
      for (int c = 0; c < 3; ++c) {
        u[c] = srgbToLinear(a.at<cv::Vec3b>(y, x)[c] / 255.f);
        v[c] = srgbToLinear(b.at<cv::Vec3b>(y, x)[c] / 255.f);
      }
      const double cosine = u.dot(v) / (cv::norm(u) * cv::norm(v) + 1e-12);
      sum += std::acos(std::clamp(cosine, -1.0, 1.0)) * 180 / CV_PI;
    }
  }
  return sum / a.total();
}

double luminanceSpread(const cv::Mat& bgr) {
  cv::Mat gray;
  cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
  cv::Scalar mean, deviation;
  cv::meanStdDev(gray, mean, deviation);
  return deviation[0];
}

}  // namespace

TEST(Lalphabeta, RoundTripIsExactFor8BitImages) {
  cv::Mat image(64, 256, CV_8UC3);
  cv::randu(image, 0, 256);
  // Include the extremes: black, white, pure primaries, greys.
  image.at<cv::Vec3b>(0, 0) = {0, 0, 0};
  image.at<cv::Vec3b>(0, 1) = {255, 255, 255};
  image.at<cv::Vec3b>(0, 2) = {255, 0, 0};
  image.at<cv::Vec3b>(0, 3) = {0, 255, 0};
  image.at<cv::Vec3b>(0, 4) = {0, 0, 255};
  for (int g = 0; g < 256; ++g) image.at<cv::Vec3b>(1, g) = {uchar(g), uchar(g), uchar(g)};
  const cv::Mat back = lalphabetaToBgr(bgrToLalphabeta(image));
  cv::Mat difference;
  cv::absdiff(image, back, difference);
  double worst = 0;
  cv::minMaxLoc(difference.reshape(1), nullptr, &worst);
  EXPECT_LE(worst, 1.0);  // at most one 8-bit level (very dark saturated colours)
  EXPECT_GE(cv::countNonZero(difference.reshape(1) == 0), 0.999 * difference.total() * 3);
}

TEST(Lalphabeta, GreysAreOnTheWhitePointAndAxesHaveTheirMeaning) {
  cv::Mat pixels(1, 4, CV_8UC3);
  pixels.at<cv::Vec3b>(0, 0) = {128, 128, 128};  // grey
  pixels.at<cv::Vec3b>(0, 1) = {255, 255, 255};  // white
  pixels.at<cv::Vec3b>(0, 2) = {255, 0, 0};      // blue
  pixels.at<cv::Vec3b>(0, 3) = {0, 0, 255};      // red
  const cv::Mat lab = bgrToLalphabeta(pixels);
  const auto grey = lab.at<cv::Vec3f>(0, 0), white = lab.at<cv::Vec3f>(0, 1);
  EXPECT_NEAR(grey[1], 0, 2e-3);
  EXPECT_NEAR(grey[2], 0, 2e-3);
  EXPECT_NEAR(white[0], 0, 2e-3);  // log10(1) = 0
  EXPECT_LT(grey[0], white[0]);
  EXPECT_LT(lab.at<cv::Vec3f>(0, 2)[1], -0.1);  // α: yellow (+) - blue (-)
  EXPECT_GT(lab.at<cv::Vec3f>(0, 3)[2], 0.1);   // β: red (+) - green (-)
  EXPECT_THROW(bgrToLalphabeta(cv::Mat(2, 2, CV_32FC3)), std::invalid_argument);
  EXPECT_THROW(lalphabetaToBgr(cv::Mat(2, 2, CV_8UC3)), std::invalid_argument);
}

TEST(ColorCorrection, RemovesASyntheticUnderwaterCast) {
  const cv::Mat scene = neutralScene(320, 240, 5);
  const cv::Mat degraded = underwater(scene);
  const CorrectedImage corrected = correctColor(degraded, ColorOptions());
  // The cast was measured (blue-green: α < 0 toward blue, β < 0 toward green) ...
  EXPECT_LT(corrected.statistics.mean_beta, -0.05);
  // ... and removed: the corrected image's chromatic means are ~0.
  const cv::Mat lab = bgrToLalphabeta(corrected.image);
  const cv::Scalar means = cv::mean(lab);
  EXPECT_NEAR(means[1], 0, 0.02);
  EXPECT_NEAR(means[2], 0, 0.02);
  // Colours: the angular error to the true scene falls by more than half.
  const double before = meanAngularError(degraded, scene);
  const double after = meanAngularError(corrected.image, scene);
  EXPECT_GT(before, 10.0);
  EXPECT_LT(after, 0.5 * before) << "before " << before << " deg, after " << after << " deg";
  // Contrast restored by the luminance stretch (the veil lifted, the range stretched).
  EXPECT_GT(luminanceSpread(corrected.image), 1.3 * luminanceSpread(degraded));
  EXPECT_TRUE(corrected.statistics.stretched);
}

TEST(ColorCorrection, NeutralImageIsLeftNeutralAndFlatImageIsNotStretched) {
  const cv::Mat scene = neutralScene(160, 120, 9);
  ColorOptions no_stretch;
  no_stretch.stretch_luminance = false;
  const CorrectedImage same = correctColor(scene, no_stretch);
  EXPECT_NEAR(same.statistics.mean_alpha, 0, 0.03);
  EXPECT_NEAR(same.statistics.mean_beta, 0, 0.03);
  EXPECT_LT(meanAngularError(same.image, scene), 2.0);
  const cv::Mat flat(50, 50, CV_8UC3, cv::Scalar(90, 140, 40));
  const CorrectedImage grey = correctColor(flat, ColorOptions());
  EXPECT_FALSE(grey.statistics.stretched);
  const cv::Vec3b pixel = grey.image.at<cv::Vec3b>(10, 10);
  EXPECT_LE(std::abs(pixel[0] - pixel[1]), 2);  // the cast of a flat colour makes it grey
  EXPECT_LE(std::abs(pixel[1] - pixel[2]), 2);
}

TEST(ColorCorrection, BadOptionsAndImagesAreRejected) {
  ColorOptions options;
  options.cutoff_low = 0.6;
  try {
    options.check();
    FAIL();
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("cutoff_low = 0.6"), std::string::npos) << e.what();
  }
  options = ColorOptions();
  options.chroma_strength = -1;
  EXPECT_THROW(options.check(), OptionError);
  EXPECT_THROW(correctColor(cv::Mat(4, 4, CV_8UC1), ColorOptions()), std::invalid_argument);
  EXPECT_THROW(correctColor(cv::Mat(), ColorOptions()), std::invalid_argument);
}

namespace {
/// A survey with keyframes/left/ (3 images 160x120) and calibration/left.yaml.
fs::path surveyWithKeyframes(const std::string& name, bool calibration) {
  const fs::path survey = freshFolder(name);
  fs::create_directories(survey / "keyframes" / "left");
  for (int i = 0; i < 3; ++i) {
    char file[64];
    std::snprintf(file, sizeof(file), "left_0001_%06d.png", i * 10);
    cv::imwrite((survey / "keyframes" / "left" / file).string(),
                underwater(neutralScene(160, 120, i)));
  }
  std::ofstream(survey / "keyframes" / "left" / "index.csv")
      << "file,video,frame,camera_time_s,sim_time_s,sharpness,motion_px,tracked\n";
  if (calibration) {
    calibration::CameraCalibration c;
    c.image_size = cv::Size(160, 120);
    c.camera_matrix = (cv::Mat_<double>(3, 3) << 150, 0, 79.5, 0, 150, 59.5, 0, 0, 1);
    c.distortion = (cv::Mat_<double>(1, 5) << 0.1, 0.02, 0, 0, 0);
    c.rms_px = 0.2;
    calibration::writeCalibration(survey / "calibration" / "left.yaml", c,
                                  calibration::CalibrationOptions());
  }
  return survey;
}
}  // namespace

TEST(CorrectStage, CorrectsUndistortsAndWritesThePinholeIntrinsics) {
  const fs::path survey = surveyWithKeyframes("stage", true);
  const CorrectStageResult result = runCorrectStage(Survey(survey), CorrectStageOptions());
  ASSERT_EQ(result.cameras.size(), 1u);
  EXPECT_EQ(result.cameras[0].images, 3);
  EXPECT_TRUE(result.cameras[0].undistorted);
  for (int i = 0; i < 3; ++i) {
    char file[64];
    std::snprintf(file, sizeof(file), "left_0001_%06d.png", i * 10);
    const cv::Mat out = cv::imread((survey / "corrected" / "left" / file).string());
    ASSERT_EQ(out.size(), cv::Size(160, 120)) << file;
  }
  EXPECT_TRUE(fs::exists(survey / "corrected" / "left" / "index.csv"));
  const calibration::CameraCalibration pinhole =
      calibration::readCalibration(survey / "corrected" / "left.yaml", "test");
  EXPECT_EQ(cv::countNonZero(pinhole.distortion), 0);
  EXPECT_EQ(pinhole.image_size, cv::Size(160, 120));
  // Pin-cushion removed with alpha 0: the valid region is enlarged, the focal length grows.
  EXPECT_GT(pinhole.camera_matrix.at<double>(0, 0), 150);
  const nlohmann::json report = readReport(survey / "report.json");
  EXPECT_EQ(report["stages"]["correct"]["cameras"]["left"]["images"], 3);
  fs::remove_all(survey);
}

TEST(CorrectStage, MissingCalibrationIsAClearErrorAndEarlierOutputStays) {
  const fs::path survey = surveyWithKeyframes("missing", false);
  fs::create_directories(survey / "corrected" / "left");
  std::ofstream(survey / "corrected" / "left" / "earlier.png") << "earlier";
  try {
    runCorrectStage(Survey(survey), CorrectStageOptions());
    FAIL() << "no calibration, yet it went on";
  } catch (const StageError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("'left'"), std::string::npos) << message;
    EXPECT_NE(message.find((survey / "calibration" / "left.yaml").string()), std::string::npos)
        << message;
    EXPECT_NE(message.find("--no-undistort"), std::string::npos) << message;
  }
  EXPECT_TRUE(fs::exists(survey / "corrected" / "left" / "earlier.png"));
  // The explicit choice: colour correction only, images keep their distortion, no intrinsics.
  CorrectStageOptions options;
  options.undistort_images = false;
  const CorrectStageResult result = runCorrectStage(Survey(survey), options);
  EXPECT_FALSE(result.cameras[0].undistorted);
  EXPECT_FALSE(fs::exists(survey / "corrected" / "left" / "earlier.png"));  // replaced
  EXPECT_FALSE(fs::exists(survey / "corrected" / "left.yaml"));
  fs::remove_all(survey);
}

TEST(CorrectStage, WithoutCalibrationTheImportPriorGivesTheIntrinsics) {
  const fs::path survey = surveyWithKeyframes("prior", false);
  // What `auv recon import` writes: the keys of a calibration, no distortion.
  calibration::CameraCalibration prior;
  prior.image_size = cv::Size(160, 120);
  prior.camera_matrix = (cv::Mat_<double>(3, 3) << 192, 0, 79.5, 0, 192, 59.5, 0, 0, 1);
  prior.distortion = cv::Mat::zeros(1, 5, CV_64F);
  calibration::writeCalibration(survey / "calibration" / "left.prior.yaml", prior,
                                calibration::CalibrationOptions());
  const CorrectStageResult result = runCorrectStage(Survey(survey), CorrectStageOptions());
  EXPECT_FALSE(result.cameras[0].undistorted);
  const calibration::CameraCalibration used =
      calibration::readCalibration(survey / "corrected" / "left.yaml", "test");
  EXPECT_DOUBLE_EQ(used.camera_matrix.at<double>(0, 0), 192.0);
  const nlohmann::json report = readReport(survey / "report.json");
  EXPECT_EQ(report["stages"]["correct"]["cameras"]["left"]["intrinsics_file"],
            (survey / "calibration" / "left.prior.yaml").string());

  // A real calibration wins over the prior (and undistorts).
  calibration::CameraCalibration c = prior;
  c.camera_matrix.at<double>(0, 0) = c.camera_matrix.at<double>(1, 1) = 150;
  c.distortion.at<double>(0) = 0.1;
  calibration::writeCalibration(survey / "calibration" / "left.yaml", c,
                                calibration::CalibrationOptions());
  EXPECT_TRUE(runCorrectStage(Survey(survey), CorrectStageOptions()).cameras[0].undistorted);

  // A keyframe of another size than the prior is named, with the prior file.
  fs::remove(survey / "calibration" / "left.yaml");
  cv::imwrite((survey / "keyframes" / "left" / "left_0001_000099.png").string(),
              cv::Mat(60, 80, CV_8UC3, cv::Scalar(1, 2, 3)));
  try {
    runCorrectStage(Survey(survey), CorrectStageOptions());
    FAIL();
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("left.prior.yaml"), std::string::npos) << e.what();
  }
  fs::remove_all(survey);
}

TEST(CorrectStage, KeyframeOfAnotherSizeThanTheCalibrationNamesBoth) {
  const fs::path survey = surveyWithKeyframes("size", true);
  cv::imwrite((survey / "keyframes" / "left" / "left_0001_000099.png").string(),
              cv::Mat(60, 80, CV_8UC3, cv::Scalar(1, 2, 3)));
  try {
    runCorrectStage(Survey(survey), CorrectStageOptions());
    FAIL();
  } catch (const StageError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("left_0001_000099.png"), std::string::npos) << message;
    EXPECT_NE(message.find("left.yaml"), std::string::npos) << message;
  }
  EXPECT_FALSE(fs::exists(survey / "corrected" / "left"));
  EXPECT_TRUE(fs::is_empty(survey / "corrected"));  // no staging folder left
  // No keyframes at all.
  const fs::path empty = freshFolder("nokeyframes");
  EXPECT_THROW(runCorrectStage(Survey(empty), CorrectStageOptions()), StageError);
  fs::remove_all(survey);
  fs::remove_all(empty);
}

TEST(CorrectStageOptions, BindTakesFlagsAndTheConfigSection) {
  const fs::path folder = freshFolder("bind");
  std::ofstream(folder / "recon.yaml")
      << "correct:\n  chroma_strength: 0.5\n  camera: [left]\n  stretch_luminance: false\n";
  CorrectStageOptions options;
  OptionSet set("correct");
  options.bind(set);
  ASSERT_TRUE(set.parse({"--config", (folder / "recon.yaml").string(), "--no-undistort", "--alpha",
                         "1", "--cutoff-high", "0.01"}));
  EXPECT_DOUBLE_EQ(options.color.chroma_strength, 0.5);
  EXPECT_EQ(options.cameras, (std::vector<std::string>{"left"}));
  EXPECT_FALSE(options.color.stretch_luminance);
  EXPECT_FALSE(options.undistort_images);
  EXPECT_TRUE(options.correct_colors);
  EXPECT_DOUBLE_EQ(options.undistort.alpha, 1.0);
  EXPECT_DOUBLE_EQ(options.color.cutoff_high, 0.01);
  EXPECT_DOUBLE_EQ(options.color.cutoff_low, ColorOptions().cutoff_low);  // default kept
  // A value of the wrong type names the file and the key.
  std::ofstream(folder / "recon.yaml") << "correct:\n  png_compression: fast\n";
  try {
    set.applyConfigFile(folder / "recon.yaml");
    FAIL() << "a non-integer png_compression was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("correct.png_compression"), std::string::npos) << e.what();
  }
  fs::remove_all(folder);
}
