#pragma once
// `auv recon evaluate <survey> --ground-truth <run>`: the reconstruction of a simulated survey
// against the simulator's ground truth (docs/paper.md §4.3, evaluator.h) -> evaluation.json.
// Not chained by `auv recon run`: it needs the simulated run.

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "auv/recon/common/stage.h"
#include "auv/recon/common/survey.h"
#include "auv/recon/evaluate/evaluator.h"

namespace auv::recon {
class OptionSet;
}

namespace auv::recon::evaluate {

struct EvaluateStageOptions {
  EvaluateOptions evaluate;
  /// The simulated run folder; empty: ground_truth_run of <survey>/simulation.json.
  std::string ground_truth;

  void check() const { evaluate.check(); }
  /// Binds the fields to flags / the `evaluate:` section of a config file.
  void bind(OptionSet& set);
};

struct EvaluateStageResult {
  nlohmann::json evaluation;  ///< what evaluation.json holds
  std::filesystem::path file;
};

/// Evaluates the survey with the texture stage's renderer of textured/model.obj. Throws
/// std::invalid_argument when no ground truth is given or recorded, StageError("evaluate", ...)
/// as evaluateSurvey().
EvaluateStageResult runEvaluateStage(const Survey& survey, const EvaluateStageOptions& options);

/// The `evaluate` stage (common/stage.h): `auv recon evaluate`, not chained by `run`.
class EvaluateStage final : public StageWith<EvaluateStageOptions> {
 public:
  std::string name() const override { return "evaluate"; }
  std::string usage() const override {
    return "<survey> --ground-truth <run>   accuracy, completeness, F-score vs the truth";
  }
  std::string surveyHelp() const override {
    return "survey folder (reads sparse/, keyframes/, dense/fused.ply, mesh/mesh.ply, "
           "textured/; writes evaluation.json)";
  }
  bool chained() const override { return false; }
  std::vector<std::filesystem::path> inputs(const Survey& survey) const override {
    return {survey.sparse(), survey.keyframes(), survey.dense(), survey.mesh(), survey.textured()};
  }
  std::vector<std::filesystem::path> outputs(const Survey& survey) const override {
    return {survey.root() / "evaluation.json"};
  }
  StageReport runWith(const Survey& survey, const EvaluateStageOptions& options) const override;
};

}  // namespace auv::recon::evaluate
