#pragma once
// `auv recon sfm <survey>`: incremental SfM over the survey's features and verified matches
// (paper section 3.4.2), written as sparse/ (COLMAP text model, points.ply, cameras.ply) and
// the `sfm` section of report.json.

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "auv/recon/common/stage.h"
#include "auv/recon/common/survey.h"
#include "auv/recon/sfm/correspondences.h"
#include "auv/recon/sfm/incremental_mapper.h"
#include "auv/recon/sfm/navigation.h"

namespace auv::recon {
class OptionSet;
}

namespace auv::recon::sfm {

struct SfmStageOptions {
  MapperOptions mapper;
  std::string loss = "cauchy";  ///< bundle adjustment loss: trivial, huber, cauchy, soft_l1
  /// Fewer images than this fraction registered: a partial result. The model that did register
  /// is written to sparse-partial/ (sparse/ kept) and the stage fails with PartialResult,
  /// naming why each image failed; with accept_partial it goes to sparse/ and the stage
  /// succeeds with a warning.
  double min_registered_ratio = 0.5;
  bool accept_partial = false;
  /// TUM trajectory of the vehicle's navigation (e.g. <run>/ground_truth/navigation.tum):
  /// the model is scaled to metres and turned into its frame (navigation.h). Empty: the
  /// survey's navigation.tum when it has one, else SfM's arbitrary frame and scale.
  std::string navigation;
  int threads = 0;  ///< Ceres threads (0: common/threads.h's defaultThreadCount())

  /// Throws OptionError naming the field and value.
  void check() const;
  /// The mapper's options with `loss` and `threads` applied.
  MapperOptions mapperOptions() const;
  /// Binds the fields to flags / the `sfm:` section of a config file.
  void bind(OptionSet& set);
};

struct SfmStageResult {
  size_t images_total = 0, images_registered = 0, points = 0, observations = 0;
  size_t cameras = 0;
  double mean_track_length = 0, mean_reprojection_error_px = 0;
  NavigationAlignment navigation;
  MapperResult mapper;  ///< (reconstruction included)
  double seconds_reading = 0, seconds_writing = 0, seconds = 0;
  /// Cameras with only a prior: their final focal (px), also in sparse/<camera>.yaml.
  std::map<std::string, double> self_calibrated;
  std::vector<std::string> warnings;  ///< runaway refinements reset, partial result accepted
  bool partial = false;               ///< fewer than min_registered_ratio registered
};

/// The SfM input of a survey: cameras from corrected/<camera>.yaml (PINHOLE, ids 1.. in camera
/// order), images and keypoints from features/ (ids 1.. in the index order), verified pairs
/// from features/matches/pairs.bin. Throws StageError("sfm", ...) naming what is missing or
/// inconsistent (a camera without calibration, a feature file of another size than its
/// camera, a pair naming an unknown image).
SfmInput readSfmInput(const Survey& survey);

/// Runs the stage: reads, reconstructs (progress bar), optionally aligns to the navigation,
/// writes sparse/ through a staging folder and the report section. Expected failures (no
/// initial pair, too few registered images) throw StageError with the numbers; earlier
/// outputs stay intact.
SfmStageResult runSfmStage(const Survey& survey, const SfmStageOptions& options);

/// Writes a model as the stage does into `folder` (cameras.txt, images.txt, points3D.txt,
/// points.ply, cameras.ply).
void writeSparseModel(const scene::Reconstruction& reconstruction,
                      const std::filesystem::path& folder);

/// The `sfm` stage (common/stage.h): `auv recon sfm` and a step of `auv recon run`.
class SfmStage final : public StageWith<SfmStageOptions> {
 public:
  std::string name() const override { return "sfm"; }
  std::string usage() const override {
    return "<survey>   incremental structure from motion (sparse model)";
  }
  std::string surveyHelp() const override {
    return "survey folder (reads corrected/, features/; writes sparse/)";
  }
  std::vector<std::filesystem::path> inputs(const Survey& survey) const override {
    return {survey.root() / "features" / "matches", survey.corrected()};
  }
  std::vector<std::filesystem::path> outputs(const Survey& survey) const override {
    return {survey.sparse()};
  }
  StageReport runWith(const Survey& survey, const SfmStageOptions& options) const override;
};

}  // namespace auv::recon::sfm
