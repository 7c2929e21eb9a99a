#pragma once
// `auv recon calibrate <survey> --camera <id> --input <video|folder>`: chessboard calibration
// of one camera (docs/paper.md §3.3, calibration.h) -> calibration/<camera>.yaml and the
// camera's entry in the `calibrate` section of report.json. Not chained by `auv recon run`: it
// needs a chessboard recording, from outside the survey.

#include <filesystem>
#include <string>
#include <vector>

#include "auv/recon/calibration/calibration.h"
#include "auv/recon/common/stage.h"
#include "auv/recon/common/survey.h"

namespace auv::recon {
class OptionSet;
}

namespace auv::recon::calibration {

struct CalibrateStageOptions {
  CalibrationOptions calibration;
  std::string camera;  ///< required: the file is calibration/<camera>.yaml
  std::string input;   ///< required: chessboard video or folder of chessboard images

  /// Throws std::invalid_argument for a missing camera or input, OptionError for a bad value.
  void check() const;
  /// Binds the fields to flags / the `calibrate:` section of a config file.
  void bind(OptionSet& set);
};

struct CalibrateStageResult {
  CameraCalibration calibration;
  std::filesystem::path file;  ///< calibration/<camera>.yaml written
};

/// Calibrates `options.camera` from `options.input` and writes its file and report entry.
/// Throws StageError("calibrate", ...) for a missing input or too few boards.
CalibrateStageResult runCalibrateStage(const Survey& survey, const CalibrateStageOptions& options);

/// The `calibrate` stage (common/stage.h): `auv recon calibrate`, not chained by `run`.
class CalibrateStage final : public StageWith<CalibrateStageOptions> {
 public:
  std::string name() const override { return "calibrate"; }
  std::string usage() const override {
    return "<survey> --camera <id> --input <video|folder>   chessboard calibration";
  }
  std::string surveyHelp() const override {
    return "survey folder (writes calibration/<camera>.yaml)";
  }
  bool chained() const override { return false; }
  std::vector<std::filesystem::path> inputs(const Survey& /*survey*/) const override { return {}; }
  std::vector<std::filesystem::path> outputs(const Survey& survey) const override {
    return {survey.calibration()};
  }
  StageReport runWith(const Survey& survey, const CalibrateStageOptions& options) const override;
};

}  // namespace auv::recon::calibration
