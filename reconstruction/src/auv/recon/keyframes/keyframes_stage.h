#pragma once
// `auv recon keyframes <survey>`: recordings/<camera>/*.mp4 -> keyframes/<camera>/ (PNG +
// index.csv + rejected.csv) and the `keyframes` section of report.json. Every camera's folder
// is written aside and swapped into place only when all cameras succeeded, so a failure
// (damaged video, bad sidecar, interruption) leaves the earlier keyframes as they were.

#include <filesystem>
#include <string>
#include <vector>

#include "auv/recon/common/stage.h"
#include "auv/recon/common/survey.h"
#include "auv/recon/keyframes/selector.h"
#include "auv/recon/keyframes/video.h"

namespace auv::recon {
class OptionSet;
}

namespace auv::recon::keyframes {

struct KeyframesStageOptions {
  KeyframeOptions selection;
  VideoOptions video;
  /// Camera ids (folders of recordings/); empty = every camera folder.
  std::vector<std::string> cameras;

  void check() const;
  /// Binds the fields to flags / the `keyframes:` section of a config file.
  void bind(OptionSet& set);
};

struct CameraKeyframes {
  std::string camera;
  std::vector<VideoKeyframes> videos;
  int frames = 0, keyframes = 0, rejected = 0;
};

struct KeyframesStageResult {
  std::vector<CameraKeyframes> cameras;
  std::vector<std::string> problems;  ///< damaged videos kept with keep_damaged
  double seconds = 0;
};

/// Runs the stage over the survey. Throws StageError naming the folder or file at fault
/// (no recordings, a camera without videos, a damaged video, ...); earlier outputs intact.
KeyframesStageResult runKeyframesStage(const Survey& survey, const KeyframesStageOptions& options);

/// Video files of a recordings/<camera>/ folder (.mp4 .avi .mov .mkv; `.part` files skipped).
std::vector<std::filesystem::path> listVideos(const std::filesystem::path& folder);

/// The `keyframes` stage (common/stage.h): `auv recon keyframes` and a step of `auv recon run`.
class KeyframesStage final : public StageWith<KeyframesStageOptions> {
 public:
  std::string name() const override { return "keyframes"; }
  std::string usage() const override {
    return "<survey>   select sharp keyframes from the recordings";
  }
  std::string surveyHelp() const override {
    return "survey folder (reads recordings/, writes keyframes/)";
  }
  std::vector<std::filesystem::path> inputs(const Survey& survey) const override {
    return {survey.recordings()};
  }
  std::vector<std::filesystem::path> outputs(const Survey& survey) const override {
    return {survey.keyframes()};
  }
  StageReport runWith(const Survey& survey, const KeyframesStageOptions& options) const override;
};

}  // namespace auv::recon::keyframes
