#pragma once
// `auv recon figures <survey>`: per-camera contribution and trajectory comparison (docs/paper.md
// §4.3, Figures 19 and 20; figures.h) -> figures/. Not chained by `auv recon run`.

#include <filesystem>
#include <string>
#include <vector>

#include "auv/recon/common/stage.h"
#include "auv/recon/common/survey.h"
#include "auv/recon/evaluate/figures.h"

namespace auv::recon {
class OptionSet;
}

namespace auv::recon::evaluate {

struct FiguresStageOptions {
  FiguresOptions figures;
  /// Simulated run folder for the alignment and the navigation; empty: ground_truth_run of
  /// <survey>/simulation.json.
  std::string ground_truth;
  /// Draw the per-camera figure in the reconstruction's own frame, no trajectory.
  bool no_ground_truth = false;

  void check() const { figures.check(); }
  /// Binds the fields to flags / the `figures:` section of a config file.
  void bind(OptionSet& set);
};

/// writeFigures() with the ground truth of the options (or the survey's recorded one).
FiguresStageResult runFiguresStage(const Survey& survey, const FiguresStageOptions& options);

/// The `figures` stage (common/stage.h): `auv recon figures`, not chained by `run`.
class FiguresStage final : public StageWith<FiguresStageOptions> {
 public:
  std::string name() const override { return "figures"; }
  std::string usage() const override {
    return "<survey>   per-camera contribution and trajectory figures (Figs. 19, 20)";
  }
  std::string surveyHelp() const override {
    return "survey folder (reads sparse/, dense/fused.ply + fused_views.bin; writes figures/)";
  }
  bool chained() const override { return false; }
  std::vector<std::filesystem::path> inputs(const Survey& survey) const override {
    return {survey.sparse(), survey.dense()};
  }
  std::vector<std::filesystem::path> outputs(const Survey& survey) const override {
    return {survey.root() / "figures"};
  }
  StageReport runWith(const Survey& survey, const FiguresStageOptions& options) const override;
};

}  // namespace auv::recon::evaluate
