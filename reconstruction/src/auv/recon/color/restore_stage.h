#pragma once
// `auv recon restore <survey>`: range-aware colour restoration (water_model.h, Sea-thru). The
// ranges of every keyframe are rendered from mesh/mesh.ply at its sparse/ pose; the water
// (backscatter, attenuation, vignetting) is fitted blind from those image/range pairs; the
// keyframes (as filmed, undistorted to the sparse/ pinhole cameras, not the lαβ-corrected ones)
// are restored into restored/<camera>/*.png with restored/water.yaml; report.json section
// `restore`. The texture stage textures from restored/ when it exists (its `images` option).

#include <filesystem>
#include <string>
#include <vector>

#include "auv/recon/color/water_model.h"
#include "auv/recon/common/stage.h"
#include "auv/recon/common/survey.h"

namespace auv::recon {
class OptionSet;
}

namespace auv::recon::color {

struct RestoreStageOptions {
  WaterFitOptions water;
  int samples_per_image = 20000;  ///< pixels per keyframe for the backscatter fit
  int max_points = 20000;         ///< mesh vertices followed across views (attenuation fit)
  double depth_tolerance = 0.01;  ///< relative z-buffer tolerance of a vertex's visibility
  int blur_px = 5;                ///< box filter of the samples (sensor noise), odd, 1 = none
  int png_compression = 1;

  void check() const;
  void bind(OptionSet& set);
};

struct RestoreStageResult {
  WaterModel model;
  BackscatterFitStats backscatter;
  AttenuationFitStats attenuation;
  size_t images = 0;
  double seconds = 0;
  /// Why the water could not be estimated (too few dark pixels or surface points seen at
  /// several ranges, ...): nothing restored, restored/ removed, texture uses corrected/.
  std::string not_restored;
};

/// restored/ of a survey.
std::filesystem::path restoredFolder(const Survey& survey);

/// Runs the stage. StageError("restore", ...) naming the file for a missing mesh, sparse model
/// or keyframe, a keyframe of another size than its camera or a distorted camera in sparse/;
/// restored/ is then left as it was. A survey whose images and ranges do not hold enough to
/// estimate the water is not an error: `not_restored` says why, restored/ (of an earlier model)
/// is removed, so that texture falls back to corrected/, and `auv recon run` goes on.
RestoreStageResult runRestoreStage(const Survey& survey, const RestoreStageOptions& options);

class RestoreStage final : public StageWith<RestoreStageOptions> {
 public:
  std::string name() const override { return "restore"; }
  std::string usage() const override {
    return "<survey>   range-aware colour restoration (water fitted from images and ranges)";
  }
  std::string surveyHelp() const override {
    return "survey folder (reads keyframes/, calibration/, sparse/, mesh/; writes restored/)";
  }
  std::vector<std::filesystem::path> inputs(const Survey& survey) const override {
    return {survey.keyframes(), survey.sparse(), survey.mesh()};
  }
  std::vector<std::filesystem::path> outputs(const Survey& survey) const override {
    return {restoredFolder(survey)};
  }
  StageReport runWith(const Survey& survey, const RestoreStageOptions& options) const override;
};

}  // namespace auv::recon::color
