#include "auv/recon/evaluate/evaluate_stage.h"

#include <iomanip>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "auv/recon/common/option_set.h"
#include "auv/recon/evaluate/change_evaluation.h"
#include "auv/recon/texture/textured_model.h"

namespace auv::recon::evaluate {
namespace {

std::string fixed(double value, int digits) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(digits) << value;
  return out.str();
}

}  // namespace

void EvaluateStageOptions::bind(OptionSet& set) {
  EvaluateOptions& o = evaluate;
  set.add("ground_truth", &ground_truth,
          "the simulated run folder (default: ground_truth_run of <survey>/simulation.json)");
  set.add("thresholds_m", &o.thresholds_m, "m: F-score distance thresholds, comma-separated");
  set.add("sample_spacing_m", &o.sample_spacing_m, "m: spacing of the true-surface samples");
  set.add("min_views", &o.min_views, "well-imaged region: keyframes that must see a point");
  set.add("max_range_m", &o.max_range_m,
          "m: well-imaged region: farthest view (0: half the water's visibility)");
  set.add("max_incidence_deg", &o.max_incidence_deg,
          "deg: well-imaged region: most oblique view of a point");
  set.add("axis_length_m", &o.axis_length_m,
          "m: alignment: points along each camera's axes (0: centres only)");
  set.add("inlier_sigmas", &o.inlier_sigmas, "alignment: inlier bound in robust sigmas");
  set.add("min_inlier_m", &o.min_inlier_m, "m: alignment: residuals always accepted");
  set.add("psnr_views", &o.psnr_views, "held-out frames rendered for the texture PSNR");
  set.add("true_texture_run", &o.true_texture_run,
          "run rendered in clear water: held-out frames also compared with it (default: "
          "simulation.json's true_texture_run)");
  set.add("write_clouds", &o.write_clouds, "also write evaluation/region.ply");
  set.add("write_views", &o.write_views,
          "also write evaluation/views/<frame>.png: filmed | model | true texture");
  set.add("seed", &o.seed, "sampling seed");
  set.add("survey_1", &o.survey_1,
          "the earlier survey of `auv recon compare` (default: survey_1 of change/report.json)");
  set.add("change_min_magnitude_m", &o.change.min_magnitude_m,
          "m: true changes smaller than this are not asked for");
  set.add("change_match_radius_m", &o.change.match_radius_m,
          "m: a change measured this near a true changed point is on it");
  set.add("change_min_hit_fraction", &o.change.min_hit_fraction,
          "share of a true region's measured points (of a cluster's points) that must be hit");
  set.add("change_min_measured_fraction", &o.change.min_measured_fraction,
          "a true region with less of it measured is `not measured` (not missed)");
  set.add("change_min_cluster_area_m2", &o.change.min_cluster_area_m2,
          "m²: smaller change clusters are not scored (0: compare's own minimum)");
}

EvaluateStageResult runEvaluateStage(const Survey& survey, const EvaluateStageOptions& options) {
  std::filesystem::path run = options.ground_truth;
  if (run.empty()) run = recordedGroundTruth(survey);
  if (run.empty()) {
    throw std::invalid_argument("--ground-truth <run folder>: required (" +
                                (survey.root() / "simulation.json").string() +
                                " names no ground_truth_run)");
  }
  // Texture fidelity: the texture stage's renderer of textured/model.obj, read once.
  std::unique_ptr<texture::TexturedModel> model;
  std::filesystem::path model_file;
  const TexturedModelRenderer renderer =
      [&](const std::filesystem::path& obj, const scene::Camera& camera,
          const Eigen::Matrix3d& rotation_cw, const Eigen::Vector3d& translation_cw, cv::Mat& image,
          cv::Mat& mask) {
        if (!model || model_file != obj) {
          model = std::make_unique<texture::TexturedModel>(texture::readObj(obj));
          model_file = obj;
        }
        texture::ViewGeometry view;
        view.camera = camera;
        view.world_to_camera.linear() = rotation_cw;
        view.world_to_camera.translation() = translation_cw;
        const texture::Rendering rendering = texture::renderTexturedModel(*model, view);
        image = rendering.image;
        mask = rendering.mask;
        return true;
      };
  EvaluateStageResult result;
  result.evaluation = evaluateSurvey(survey, run, options.evaluate, renderer);
  result.file = survey.root() / "evaluation.json";
  return result;
}

StageReport EvaluateStage::runWith(const Survey& survey,
                                   const EvaluateStageOptions& options) const {
  const EvaluateStageResult evaluated = runEvaluateStage(survey, options);
  const nlohmann::json& result = evaluated.evaluation;
  StageReport report;
  const auto& images = result["images"];
  const auto& error = result["camera_error"]["position_m"];
  std::ostringstream line;
  line << "evaluate: " << images["matched_to_truth"] << " of " << images["registered"]
       << " registered images matched to ground truth, " << images["keyframes"]
       << " keyframes; alignment scale " << fixed(result["alignment"]["scale"], 4)
       << ", camera position error median " << fixed(error["median"], 3) << " m (max "
       << fixed(error["max"], 3) << " m)";
  report.lines.push_back(line.str());
  report.summary = "camera position error median " + fixed(error["median"], 3) + " m";
  line.str("");
  line << "evaluate: well-imaged region " << fixed(result["region"]["area_well_imaged_m2"], 1)
       << " m2 (seen by >= " << options.evaluate.min_views << " keyframes within "
       << fixed(result["region"]["max_range_m"], 1) << " m)";
  report.lines.push_back(line.str());
  for (const auto& [name, s] : result["surfaces"].items()) {
    line.str("");
    line << "evaluate: " << std::left << std::setw(6) << name << std::right;
    for (const auto& t : s["thresholds"]) {
      line << "  F@" << fixed(t["threshold_m"].get<double>() * 100, 0) << "cm "
           << fixed(t["fscore"], 3) << " (P " << fixed(t["precision"], 3) << " R "
           << fixed(t["recall"], 3) << ")";
    }
    report.lines.push_back(line.str());
  }
  const auto& texture = result["texture"];
  line.str("");
  line << "evaluate: texture: " << texture["status"].get<std::string>();
  if (texture.contains("median_psnr_db") && !texture["median_psnr_db"].is_null()) {
    line << ", median PSNR " << fixed(texture["median_psnr_db"], 2) << " dB ("
         << fixed(texture["median_psnr_gain_offset_db"], 2)
         << " dB after per-channel gain/offset) against the filmed frames";
  }
  if (texture.contains("median_psnr_true_texture_db")) {
    line << "; " << fixed(texture["median_psnr_true_texture_db"], 2) << " dB ("
         << fixed(texture["median_psnr_true_texture_gain_offset_db"], 2)
         << " dB) against the true texture, CIEDE2000 "
         << fixed(texture["median_delta_e_2000_true_texture"], 2);
  }
  report.lines.push_back(line.str());
  report.lines.push_back("evaluate: change: " + changeSummary(result["change"]));
  report.lines.push_back("evaluate: " + fixed(result["seconds"], 1) + " s -> " +
                         evaluated.file.string());
  return report;
}

}  // namespace auv::recon::evaluate
