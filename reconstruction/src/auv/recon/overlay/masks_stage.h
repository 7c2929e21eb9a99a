#pragma once
// `auv recon masks <survey>`: checks the survey's masks (masks/mask.h) against the keyframes
// they mask, and with --detect-overlay writes masks/<camera>.png from the static overlay of the
// camera's videos (overlay_detector.h). The `masks` section of report.json.

#include <filesystem>
#include <string>
#include <vector>

#include "auv/recon/common/stage.h"
#include "auv/recon/common/survey.h"
#include "auv/recon/overlay/overlay_detector.h"

namespace auv::recon {
class OptionSet;
}

namespace auv::recon::overlay {

struct MasksStageOptions {
  /// Detect the static overlay of each camera's videos and write masks/<camera>.png.
  bool detect_overlay = false;
  /// Overwrite an existing masks/<camera>.png (a user's mask is never replaced otherwise).
  bool replace = false;
  /// Only these cameras; empty: every camera folder of recordings/ (detection) or keyframes/.
  std::vector<std::string> cameras;
  OverlayOptions overlay;

  void check() const;
  /// Binds the fields to flags / the `masks:` section of a config file.
  void bind(OptionSet& set);
};

struct CameraMaskReport {
  std::string camera;
  bool camera_mask = false;    ///< masks/<camera>.png exists (after detection)
  size_t image_masks = 0;      ///< masks/<camera>/<image>.png files
  size_t images_checked = 0;   ///< keyframes whose mask was loaded and size-checked
  bool detected = false;       ///< this run wrote masks/<camera>.png
  OverlayDetection detection;  ///< when detected
  std::vector<std::string> videos;
};

struct MasksStageResult {
  std::vector<CameraMaskReport> cameras;
  double seconds = 0;
};

/// Runs the stage. Throws StageError naming the file at fault: a mask of the wrong size or
/// unreadable, an existing masks/<camera>.png without `replace`, a camera without videos, a
/// scene that does not move enough for the detector.
MasksStageResult runMasksStage(const Survey& survey, const MasksStageOptions& options);

/// The `masks` stage (common/stage.h): `auv recon masks`; not chained by `auv recon run`
/// (a detected mask is for the user to inspect before it is used).
class MasksStage final : public StageWith<MasksStageOptions> {
 public:
  std::string name() const override { return "masks"; }
  std::string usage() const override {
    return "<survey>   check masks/, or detect burned-in overlays (--detect-overlay)";
  }
  std::string surveyHelp() const override {
    return "survey folder (reads recordings/, keyframes/, masks/; writes masks/<camera>.png)";
  }
  bool chained() const override { return false; }
  std::vector<std::filesystem::path> inputs(const Survey& survey) const override {
    return {survey.recordings()};
  }
  std::vector<std::filesystem::path> outputs(const Survey& survey) const override {
    return {survey.root() / "masks"};
  }
  StageReport runWith(const Survey& survey, const MasksStageOptions& options) const override;
};

}  // namespace auv::recon::overlay
