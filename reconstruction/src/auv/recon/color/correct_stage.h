#pragma once
// `auv recon correct <survey>`: keyframes/<camera>/*.png -> corrected/<camera>/*.png, colour
// corrected (section 3.2, correction.h) and undistorted with calibration/<camera>.yaml (section
// 3.3, calibration/undistort.h), plus corrected/<camera>.yaml, the pinhole intrinsics of the
// corrected images (same keys, zero distortion), and the `correct` section of report.json.
// Camera folders are written aside and swapped into place only when every camera succeeded.

#include <filesystem>
#include <string>
#include <vector>

#include "auv/recon/calibration/undistort.h"
#include "auv/recon/color/correction.h"
#include "auv/recon/common/stage.h"
#include "auv/recon/common/survey.h"

namespace auv::recon {
class OptionSet;
}

namespace auv::recon::color {

struct CorrectStageOptions {
  ColorOptions color;
  calibration::UndistortOptions undistort;
  /// false (--no-undistort): the images keep their lens distortion and no calibration is
  /// needed; corrected/<camera>.yaml is then a copy of the calibration when there is one.
  bool undistort_images = true;
  bool correct_colors = true;  ///< false (--no-correct-colors): undistortion only
  int png_compression = 1;     ///< cv::IMWRITE_PNG_COMPRESSION, 0-9
  /// Camera ids (folders of keyframes/); empty = every camera folder.
  std::vector<std::string> cameras;

  void check() const;
  /// Binds the fields to flags / the `correct:` section of a config file.
  void bind(OptionSet& set);
};

struct CameraCorrection {
  std::string camera;
  int images = 0;
  bool undistorted = false;
  double mean_alpha = 0, mean_beta = 0;  ///< average cast removed (lαβ)
  double seconds = 0;
};

struct CorrectStageResult {
  std::vector<CameraCorrection> cameras;
  double seconds = 0;
};

/// Runs the stage. Throws StageError naming the camera and the file at fault (no keyframes,
/// missing or malformed calibration, an image of another size than the calibration's, an
/// unreadable image); earlier outputs intact.
CorrectStageResult runCorrectStage(const Survey& survey, const CorrectStageOptions& options);

/// The `correct` stage (common/stage.h): `auv recon correct` and a step of `auv recon run`.
class CorrectStage final : public StageWith<CorrectStageOptions> {
 public:
  std::string name() const override { return "correct"; }
  std::string usage() const override {
    return "<survey>   colour-correct and undistort the keyframes";
  }
  std::string surveyHelp() const override {
    return "survey folder (reads keyframes/ and calibration/, writes corrected/)";
  }
  std::vector<std::filesystem::path> inputs(const Survey& survey) const override {
    return {survey.keyframes(), survey.calibration()};
  }
  std::vector<std::filesystem::path> outputs(const Survey& survey) const override {
    return {survey.corrected()};
  }
  StageReport runWith(const Survey& survey, const CorrectStageOptions& options) const override;
};

}  // namespace auv::recon::color
