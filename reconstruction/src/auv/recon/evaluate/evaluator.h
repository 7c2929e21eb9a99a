#pragma once
// `auv recon evaluate <survey> --ground-truth <run>`: the reconstruction of a simulated survey
// measured against the simulator's truth (issue 7, "Accuracy tooling"; README.md here):
//   1. survey images -> ground-truth frames (image_matching.h);
//   2. similarity reconstruction -> truth from the camera poses, camera pose errors
//      (alignment.h);
//   3. the well-imaged region of the true surface (well_imaged_region.h);
//   4. accuracy, completeness and F-score of the sparse cloud, the dense cloud and the mesh
//      (surface_metrics.h);
//   5. texture PSNR at held-out frames, when a renderer of the textured model is given
//      (image_metrics.h);
//   6. when the survey was compared with an earlier one (`auv recon compare`) and its run has
//      the simulator's change truth: the change found against the true change
//      (change_evaluation.h).
// Writes <survey>/evaluation.json and the `evaluate` section of report.json.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "auv/recon/common/survey.h"
#include "auv/recon/evaluate/change_scores.h"
#include "auv/recon/scene/camera.h"

namespace auv::recon::evaluate {

struct EvaluateOptions {
  /// Distance thresholds of the F-scores, m, comma-separated.
  std::string thresholds_m = "0.02,0.05,0.1,0.2";
  /// m: mean spacing of the samples of the true surface (recall's Monte Carlo estimate).
  double sample_spacing_m = 0.02;
  /// Well-imaged region: keyframes that must see a point.
  int min_views = 2;
  /// m: farthest a keyframe counts as seeing a point; 0 = half the scenario's water
  /// visibility (contrast still 14 %; 2.25 m when the scenario gives no visibility).
  double max_range_m = 0;
  /// deg: most oblique view of a surface point that counts.
  double max_incidence_deg = 80;
  /// Alignment: axis points (m), inlier rule (robust sigmas, floor in m).
  double axis_length_m = 1.0;
  double inlier_sigmas = 3.0;
  double min_inlier_m = 0.05;
  /// Held-out frames rendered for the texture PSNR (over all cameras).
  int psnr_views = 12;
  /// A run rendered like the ground truth but in clear water, without noise, vignetting or
  /// motion blur (reconstruction/bench/pipeline/render_true_texture.sh): its frames are the
  /// true texture the held-out views are also compared with. Empty: simulation.json's
  /// "true_texture_run", if any.
  std::string true_texture_run;
  /// Also write evaluation/region.ply (true samples coloured by region) and the aligned
  /// clouds with their errors, for viewing.
  bool write_clouds = false;
  /// Also write evaluation/views/<frame>.png for each held-out frame: filmed | textured model |
  /// true texture, side by side.
  bool write_views = false;
  int64_t seed = 1;
  /// The change against the truth (change_scores.h).
  ChangeScoreOptions change;
  /// The earlier survey of a comparison; empty: the survey_1 that change/report.json records.
  std::string survey_1;

  /// The thresholds as numbers; throws OptionError naming thresholds_m.
  std::vector<double> thresholds() const;
  /// Throws OptionError naming the field and value.
  void check() const;
};

/// Renders the textured model (textured/model.obj) seen by an undistorted camera at a pose in
/// the model's frame; fills `image` (CV_8UC3 BGR) and `mask` (CV_8U, non-zero where the model
/// is seen). Returns false when it cannot render (the texture stage provides one).
using TexturedModelRenderer =
    std::function<bool(const std::filesystem::path& model, const scene::Camera& camera,
                       const Eigen::Matrix3d& rotation_cw, const Eigen::Vector3d& translation_cw,
                       cv::Mat& image, cv::Mat& mask)>;

/// Runs the evaluation and returns what it wrote to <survey>/evaluation.json. Throws
/// StageError("evaluate", ...) when the survey has no sparse model, the ground truth is
/// missing, or too few images match it; OptionError for bad options.
nlohmann::json evaluateSurvey(const Survey& survey, const std::filesystem::path& ground_truth_run,
                              const EvaluateOptions& options,
                              const TexturedModelRenderer& renderer = {});

/// The run folder a survey records under `key` in <survey>/simulation.json (relative to the
/// survey folder); empty when it records none. Throws StageError for a malformed file.
std::filesystem::path recordedRun(const Survey& survey, const std::string& key);
/// recordedRun(survey, "ground_truth_run").
std::filesystem::path recordedGroundTruth(const Survey& survey);

}  // namespace auv::recon::evaluate
