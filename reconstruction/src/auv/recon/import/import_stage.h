#pragma once
// `auv recon import <survey> --images DIR | --video FILE [--camera ID]`: footage from anywhere
// into a survey. Photos (a diver's stills, an ROV's frame grabs, a phone's pictures) land as
// keyframes, turned upright as their EXIF says: keyframes/<camera>/<stem>.png + index.csv; a
// folder of mixed cameras or sizes becomes one camera per group. A video lands in
// recordings/<camera>/ with its frames sidecar, for the keyframes stage. Each camera gets an
// intrinsics prior, calibration/<camera>.prior.yaml (intrinsics_prior.h). Not chained by
// `auv recon run`: the footage comes from outside the survey.
//
// Unreadable files (corrupt, truncated, not an image) are skipped and named; nothing already in
// the survey is overwritten unless --replace is given, and a failing import writes nothing.

#include <filesystem>
#include <string>
#include <vector>

#include "auv/recon/common/stage.h"
#include "auv/recon/common/survey.h"
#include "auv/recon/import/intrinsics_prior.h"

namespace auv::recon {
class OptionSet;
}

namespace auv::recon::import {

struct ImportStageOptions {
  std::string images;  ///< folder of photos (one of images and video)
  std::string video;   ///< one video file (.mp4 .avi .mov .mkv)
  /// Camera id (a folder name). Default: the images folder's name, or the video's stem. A folder
  /// with several camera groups gives <camera>, <camera>-2, ... (largest group first).
  std::string camera;
  bool replace = false;  ///< replace keyframes/<camera> / a video of the same name
  PriorOptions prior;
  int png_compression = 1;

  /// Throws std::invalid_argument (exit 2) for a missing or doubled source, a bad camera id, or
  /// a value out of range.
  void check() const;
  void bind(OptionSet& set);
};

/// A camera id made from a folder name or a video stem: ',' and '/' become '_', a leading '.'
/// too, and an empty name is "camera" (camera ids are folder names and CSV fields).
std::string cameraIdFrom(const std::string& name);

/// One file that was not imported, and why.
struct SkippedFile {
  std::string file;
  std::string reason;
};

struct ImportedCamera {
  std::string camera;
  std::string kind;        ///< "images" or "video"
  int images = 0;          ///< photos imported (videos: 0)
  int frames = 0;          ///< video frames decoded (photos: 0)
  int upright_turned = 0;  ///< photos turned or mirrored by their EXIF orientation
  int with_time = 0;       ///< photos with an EXIF capture time
  std::string group;       ///< what the group shares ("2832x2128 KODAK Z612 ZOOM, 5.8 mm")
  IntrinsicsPrior prior;
  std::vector<std::filesystem::path> written;  ///< folders / files written in the survey
};

struct ImportStageResult {
  std::vector<ImportedCamera> cameras;
  std::vector<SkippedFile> skipped;
  std::vector<std::string> warnings;  ///< skipped files, EXIF not used, damaged video
  double seconds = 0.0;
};

/// Imports `options.images` or `options.video` into `survey`, and its `import` section of
/// report.json. Throws StageError("import", ...) naming the file or folder when nothing can be
/// imported or a destination is taken (without --replace); the survey is then as it was.
ImportStageResult runImportStage(const Survey& survey, const ImportStageOptions& options);

class ImportStage final : public StageWith<ImportStageOptions> {
 public:
  std::string name() const override { return "import"; }
  std::string usage() const override {
    return "<survey> --images <folder> | --video <file> [--camera <id>]   footage from anywhere";
  }
  std::string surveyHelp() const override {
    return "survey folder (created if missing; writes keyframes/<camera>/ or "
           "recordings/<camera>/, and calibration/<camera>.prior.yaml)";
  }
  bool chained() const override { return false; }
  std::vector<std::filesystem::path> inputs(const Survey& /*survey*/) const override { return {}; }
  std::vector<std::filesystem::path> outputs(const Survey& survey) const override {
    return {survey.keyframes(), survey.recordings()};
  }
  StageReport runWith(const Survey& survey, const ImportStageOptions& options) const override;
};

}  // namespace auv::recon::import
