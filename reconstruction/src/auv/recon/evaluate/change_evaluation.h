#pragma once
// `auv recon evaluate <survey-2>` on a survey that `auv recon compare <survey-1> <survey-2>`
// compared with an earlier one, in a simulated site that changed between the visits: the
// comparison (<survey-2>/change/changes.ply and report.json, in survey 1's reconstruction
// frame) is brought into the world frame by survey 1's own similarity to its truth (its
// simulation.json's ground_truth_run, survey_truth.h) and scored against the change the
// simulator wrote into survey 2's run (change_truth.h, change_scores.h; the colour's change:
// appearance_scores.h), within the region both visits imaged well. README.md, "Change against
// the truth".

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "auv/recon/common/survey.h"
#include "auv/recon/evaluate/evaluator.h"
#include "auv/recon/evaluate/survey_truth.h"

namespace auv::recon::evaluate {

/// The `change` section of evaluation.json. `status` is "evaluated" or "not evaluated" with
/// `why` (no compare output: "run auv recon compare <survey-1> <survey-2>"; no changes.json in
/// the truth; survey 1 not found or without ground truth); when evaluated, its `appearance`
/// object is the colour's change scored, or "not evaluated" with `why` (a changes.ply of an
/// older compare, without scalar_delta_e / scalar_appearance_significant; no colours compared)
/// while the shape's scores stand. `region2` is survey 2's well-imaged region
/// (evaluateSurvey's). Throws StageError("evaluate", ...) naming the file and field of a
/// malformed changes.json, changes.ply or change/report.json, or when survey 1 cannot be
/// aligned to its truth.
nlohmann::json evaluateChange(const Survey& survey, const std::filesystem::path& ground_truth_run,
                              const WellImagedSamples& region2, const EvaluateOptions& options);

/// The one-line reason or headline of a `change` section, for the stage's output.
std::string changeSummary(const nlohmann::json& change);

}  // namespace auv::recon::evaluate
