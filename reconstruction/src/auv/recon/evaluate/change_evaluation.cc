#include "auv/recon/evaluate/change_evaluation.h"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

#include <open3d/geometry/KDTreeFlann.h>
#include <open3d/t/geometry/PointCloud.h>
#include <open3d/t/io/PointCloudIO.h>

#include "auv/recon/common/stage_error.h"
#include "auv/recon/evaluate/appearance_scores.h"
#include "auv/recon/evaluate/change_scores.h"
#include "auv/recon/evaluate/change_truth.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace auv::recon::evaluate {
namespace {

constexpr const char* kStage = "evaluate";
// What compare uses when its report gives no options (compare_stage.h's defaults).
constexpr double kCompareCoreSpacingM = 0.2;
constexpr double kCompareMinClusterAreaM2 = 0.05;

json notEvaluated(const std::string& why) { return {{"status", "not evaluated"}, {"why", why}}; }

json readJson(const fs::path& file) {
  try {
    std::ifstream in(file);
    if (!in) throw std::runtime_error("cannot be read");
    return json::parse(in);
  } catch (const std::exception& e) {
    throw StageError(kStage, file.string() + ": " + e.what());
  }
}

/// compare's change/changes.ply: the core points with normals, scalar_distance and
/// scalar_significant (survey 1's reconstruction frame), and scalar_delta_e and
/// scalar_appearance_significant when compare wrote them (`missing` names those it did not).
WorldChange readComparison(const fs::path& file, std::string& missing) {
  open3d::t::geometry::PointCloud cloud;
  if (!open3d::t::io::ReadPointCloud(file.string(), cloud,
                                     open3d::t::io::ReadPointCloudOption("ply"))) {
    throw StageError(kStage, file.string() + ": unreadable PLY");
  }
  if (!cloud.HasPointPositions() || !cloud.HasPointNormals()) {
    throw StageError(kStage, file.string() + ": no vertex properties x y z nx ny nz");
  }
  for (const char* property : {"scalar_distance", "scalar_significant"}) {
    if (!cloud.HasPointAttr(property)) {
      throw StageError(kStage, file.string() + ": no vertex property \"" + property + "\"");
    }
  }
  namespace core = open3d::core;
  const core::Tensor xyz = cloud.GetPointPositions().To(core::Float64).Contiguous();
  const core::Tensor normals = cloud.GetPointNormals().To(core::Float64).Contiguous();
  const size_t n = static_cast<size_t>(xyz.GetLength());
  // One float property of every vertex, as doubles; flags are 0/1 floats.
  auto scalars = [&cloud, n](const char* property) {
    const core::Tensor t =
        cloud.GetPointAttr(property).To(core::Float64).Reshape({-1}).Contiguous();
    return std::vector<double>(t.GetDataPtr<double>(), t.GetDataPtr<double>() + n);
  };
  auto flags = [&scalars](const char* property) {
    std::vector<char> out;
    for (double v : scalars(property)) out.push_back(v > 0.5 ? 1 : 0);
    return out;
  };
  WorldChange change;
  for (size_t i = 0; i < n; ++i) {
    const double* p = xyz.GetDataPtr<double>() + 3 * i;
    const double* q = normals.GetDataPtr<double>() + 3 * i;
    change.points.emplace_back(p[0], p[1], p[2]);
    change.normals.emplace_back(q[0], q[1], q[2]);
  }
  change.distances = scalars("scalar_distance");
  change.significant = flags("scalar_significant");
  // Two scales (compare's detection_scale > 1): the regions are made of the coarse flags.
  if (cloud.HasPointAttr("scalar_detection_significant") &&
      cloud.HasPointAttr("scalar_detection_distance")) {
    change.measuring_significant = change.significant;
    change.significant = flags("scalar_detection_significant");
    change.detection_distances = scalars("scalar_detection_distance");
  }
  if (cloud.HasPointAttr("scalar_level_of_detection"))
    change.levels_of_detection = scalars("scalar_level_of_detection");
  // The appearance fields came later: an older compare's file has the shape's change only.
  missing.clear();
  for (const char* property : {"scalar_delta_e", "scalar_appearance_significant"}) {
    if (!cloud.HasPointAttr(property)) {
      missing += (missing.empty() ? "" : ", ") + std::string(property);
    }
  }
  if (!missing.empty()) return change;
  change.delta_e = scalars("scalar_delta_e");
  change.appearance_significant = flags("scalar_appearance_significant");
  return change;
}

/// Survey 1 as given (--survey-1), else as change/report.json records it: as written (absolute
/// or relative to where compare ran), then beside survey 2.
fs::path findSurvey1(const Survey& survey, const json& report, const fs::path& report_file,
                     const EvaluateOptions& options, std::string& why) {
  std::string recorded = options.survey_1;
  if (recorded.empty()) {
    if (!report.contains("survey_1") || !report["survey_1"].is_string()) {
      why = report_file.string() + " records no survey_1: give --survey-1";
      return {};
    }
    recorded = report["survey_1"].get<std::string>();
  }
  const fs::path path = recorded;
  std::vector<fs::path> candidates = {path};
  if (path.is_relative() && options.survey_1.empty()) {
    candidates.push_back(survey.root().parent_path() / path.filename());
  }
  for (const fs::path& candidate : candidates) {
    if (fs::is_directory(candidate / "sparse")) return candidate;
  }
  why = "survey 1 " + recorded + " (" +
        (options.survey_1.empty() ? "survey_1 of " + report_file.string() : "--survey-1") +
        ") not found or has no sparse/ model";
  return {};
}

/// Per core point: in the well-imaged region of both visits. Survey 1's surface is at the core
/// point, survey 2's at the far end of its measured distance; each must have a well-imaged
/// true sample within `tolerance_m`.
std::vector<char> inBothRegions(const WorldChange& change, const WellImagedSamples& region1,
                                const WellImagedSamples& region2, double tolerance_m) {
  auto wellImaged = [](const WellImagedSamples& region) {
    std::vector<Eigen::Vector3d> points;
    for (size_t i = 0; i < region.samples.size(); ++i) {
      if (region.well_imaged[i]) points.push_back(region.samples.points[i]);
    }
    Eigen::MatrixXd matrix(3, static_cast<Eigen::Index>(points.size()));
    for (size_t i = 0; i < points.size(); ++i) matrix.col(static_cast<Eigen::Index>(i)) = points[i];
    return matrix;
  };
  const Eigen::MatrixXd samples1 = wellImaged(region1), samples2 = wellImaged(region2);
  std::vector<char> inside(change.points.size(), 0);
  if (samples1.cols() == 0 || samples2.cols() == 0) return inside;
  const open3d::geometry::KDTreeFlann tree1(samples1), tree2(samples2);  // refer to the matrices
  std::vector<int> index;
  std::vector<double> distance2;
  const double tolerance2 = tolerance_m * tolerance_m;
  for (size_t i = 0; i < change.points.size(); ++i) {
    const Eigen::Vector3d later =
        change.measured(i)
            ? Eigen::Vector3d(change.points[i] + change.distances[i] * change.normals[i])
            : change.points[i];
    const bool seen1 =
        tree1.SearchKNN(change.points[i], 1, index, distance2) > 0 && distance2[0] <= tolerance2;
    const bool seen2 =
        tree2.SearchKNN(later, 1, index, distance2) > 0 && distance2[0] <= tolerance2;
    inside[i] = seen1 && seen2;
  }
  return inside;
}

/// The `appearance` object of the change section: scored, or why not (an older compare's
/// changes.ply, clouds without colours).
json evaluateAppearance(const ChangeTruth& truth, const WorldChange& change,
                        const std::string& missing, const json& report,
                        const fs::path& changes_file, const ChangeScoreOptions& options) {
  if (!missing.empty()) {
    return notEvaluated(changes_file.string() + " has no " + missing +
                        ": written by an older auv recon compare; run it again to score the "
                        "appearance");
  }
  const json compared = report.value("appearance", json::object());
  size_t colour = 0, significant = 0;
  for (size_t i = 0; i < change.points.size(); ++i) {
    colour += change.colourMeasured(i) ? 1 : 0;
    significant += change.colourMeasured(i) && change.appearance_significant[i] ? 1 : 0;
  }
  if (colour == 0) {
    const std::string why = compared.value("why", std::string());
    return notEvaluated("compare compared no colours" + (why.empty() ? "" : " (" + why + ")"));
  }
  const AppearanceScores scores = scoreAppearance(truth, change, options);
  json result = appearanceScoresJson(scores, truth);
  const json listed = compared.value("clusters", json::array());
  result["compare"] = {
      {"core_points_colour_measured", colour},
      {"core_points_significant", significant},
      {"clusters_in_report", listed.is_array() ? json(listed.size()) : json(nullptr)},
      {"clusters_rebuilt", scores.clusters.size()}};
  return result;
}

json alignmentJson(const SurveyAlignment& aligned) {
  const AlignmentResult& a = aligned.alignment;
  return {{"scale", a.similarity.scale},
          {"images", aligned.pairs.size()},
          {"inliers", a.num_inliers},
          {"robust_sigma_m", a.robust_sigma_m},
          {"camera_position_error_median_m", aligned.errors.median_position_m},
          {"camera_position_error_rms_m", aligned.errors.rms_position_m}};
}

/// `value` with `digits` decimals (times `factor`), n/a when not a number (null: NaN).
std::string fixed(const json& value, int digits, double factor = 1.0) {
  if (!value.is_number()) return "n/a";
  std::ostringstream out;
  out << std::fixed << std::setprecision(digits) << factor * value.get<double>();
  return out.str();
}

/// The colour's scores in one clause of changeSummary's line.
std::string appearanceClause(const json& change) {
  if (!change.contains("appearance")) return "appearance not scored";
  const json& a = change["appearance"];
  if (a.value("status", "") != "evaluated") {
    return "appearance not evaluated: " + a.value("why", std::string());
  }
  const json& r = a["regions_scored"];
  const json& c = a["clusters_scored"];
  const json& s = a["stable"];
  std::ostringstream clause;
  clause << "appearance: " << r["detected"].get<size_t>() << " of "
         << r["detected"].get<size_t>() + r["missed"].get<size_t>()
         << " measured albedo regions detected (" << r["not_measured"].get<size_t>()
         << " not measured), precision " << fixed(c["precision"], 2) << " ("
         << c["true"].get<size_t>() << " true, " << c["false"].get<size_t>() << " false, "
         << c["explained_by_geometry"].get<size_t>() << " explained by geometry), false "
         << fixed(s["false_cluster_area_m2"], 2) << " m2 in clusters ("
         << fixed(s["false_fraction"], 2, 100.0) << " % of the stable core points with a colour)";
  return clause.str();
}

}  // namespace

json evaluateChange(const Survey& survey, const fs::path& ground_truth_run,
                    const WellImagedSamples& region2, const EvaluateOptions& options) {
  const fs::path report_file = survey.root() / "change" / "report.json";
  const fs::path changes_file = survey.root() / "change" / "changes.ply";
  if (!fs::exists(report_file) || !fs::exists(changes_file)) {
    return notEvaluated("no compare output (" + report_file.string() +
                        "): run auv recon compare <survey-1> " + survey.root().string());
  }
  const fs::path truth_file = changeTruthFile(ground_truth_run);
  if (!fs::exists(truth_file)) {
    return notEvaluated("the ground truth has no changes.json (" + truth_file.string() + ")");
  }
  const json report = readJson(report_file);
  std::string why;
  const fs::path survey1_path = findSurvey1(survey, report, report_file, options, why);
  if (survey1_path.empty()) return notEvaluated(why);
  const Survey survey1(survey1_path);
  const fs::path run1 = recordedGroundTruth(survey1);
  if (run1.empty()) {
    return notEvaluated("survey 1 " + survey1_path.string() +
                        " records no ground_truth_run in its simulation.json");
  }
  const ChangeTruth truth = readChangeTruth(truth_file);

  // Survey 1's reconstruction frame -> world: its similarity to its own truth.
  const GroundTruth truth1 = GroundTruth::load(run1);
  const SurveyAlignment aligned1 = alignSurveyToTruth(survey1, truth1, options);
  const Similarity& sim = aligned1.alignment.similarity;
  std::string appearance_missing;
  WorldChange change = readComparison(changes_file, appearance_missing);
  const json compare_options = report.value("options", json::object());
  change.core_spacing_m = sim.scale * compare_options.value("core_spacing_m", kCompareCoreSpacingM);
  change.min_cluster_area_m2 =
      sim.scale * sim.scale *
      compare_options.value("min_cluster_area_m2", kCompareMinClusterAreaM2);
  change.min_change_m = sim.scale * compare_options.value("min_change_m", 0.0);
  change.volume_margin_m = sim.scale * compare_options.value("volume_margin_m", 0.0);
  change.region_confidence = compare_options.value("region_confidence", 0.0);
  change.grow_regions = compare_options.value("grow_regions", false);
  change.region_footprint_m2 =
      sim.scale * sim.scale * compare_options.value("region_footprint_m2", 0.0);
  change.level_of_detection_z = compare_options.value("level_of_detection_z", 1.96);
  for (size_t i = 0; i < change.points.size(); ++i) {
    change.points[i] = sim.apply(change.points[i]);
    change.normals[i] = sim.rotation * change.normals[i];
    change.distances[i] *= sim.scale;
    if (!change.levels_of_detection.empty()) change.levels_of_detection[i] *= sim.scale;
  }
  const WellImagedSamples region1 =
      wellImagedRegion(truth1, keyframeViews(truth1, aligned1), options);
  // A core point stands for a core spacing's square of surface: well imaged when there is
  // well-imaged true surface within that of it.
  change.in_region = inBothRegions(change, region1, region2, change.core_spacing_m);
  size_t inside = 0, measured_inside = 0;
  for (size_t i = 0; i < change.points.size(); ++i) {
    inside += change.in_region[i] ? 1 : 0;
    measured_inside += change.in_region[i] && change.measured(i) ? 1 : 0;
  }

  const ChangeScores scores = scoreChanges(truth, change, options.change);
  json result = changeScoresJson(scores, truth, options.change);
  result["status"] = "evaluated";
  result["truth"] = {{"file", truth.json_file.string()},
                     {"scenario", truth.scenario},
                     {"regions", truth.regions.size()},
                     {"points", truth.points.size()}};
  result["compare"] = {{"file", changes_file.string()},
                       {"core_points", change.points.size()},
                       {"core_spacing_m", change.core_spacing_m},
                       {"clusters_in_report", report.value("clusters", json::array()).size()},
                       {"clusters_rebuilt", scores.clusters.size()}};
  const json registration = report.value("registration", json::object());
  result["registration"] = {
      {"rms_m", registration.value("rms_m", json(nullptr))},
      {"overlap", registration.value("overlap", json(nullptr))},
      {"stable_fraction", registration.value("stable_fraction", json(nullptr))}};
  result["survey_1"] = {{"path", survey1_path.string()},
                        {"ground_truth_run", run1.string()},
                        {"alignment", alignmentJson(aligned1)}};
  result["region"] = {
      {"definition",
       "core points with well-imaged true surface of visit 1 within a core spacing of them and "
       "of visit 2 within a core spacing of their measured far end"},
      {"core_points_in_both", inside},
      {"core_points_measured_in_both", measured_inside},
      {"visit_1_samples_well_imaged", region1.count},
      {"visit_2_samples_well_imaged", region2.count}};
  result["appearance"] =
      evaluateAppearance(truth, change, appearance_missing, report, changes_file, options.change);
  return result;
}

std::string changeSummary(const json& change) {
  if (change.value("status", "") != "evaluated") return change.value("why", "");
  const json& r = change["regions_scored"];
  const json& c = change["clusters_scored"];
  const json& s = change["stable"];
  std::ostringstream line;
  line << r["detected"].get<size_t>() << " of "
       << r["detected"].get<size_t>() + r["missed"].get<size_t>()
       << " measured true regions detected (recall " << fixed(r["recall_measured"], 2) << "; "
       << r["not_measured"].get<size_t>() << " not measured), precision "
       << fixed(c["precision"], 2) << " (" << c["true"].get<size_t>() << " true, "
       << c["false"].get<size_t>() << " false clusters), false change "
       << fixed(s["false_area_m2"], 2) << " m2 (" << fixed(s["false_fraction"], 2, 100.0)
       << " % of the stable core points); " << appearanceClause(change)
       << "; survey 1 aligned to its truth with camera error "
       << fixed(change["survey_1"]["alignment"]["camera_position_error_median_m"], 3)
       << " m, compare's registration rms " << fixed(change["registration"]["rms_m"], 3) << " m";
  return line.str();
}

}  // namespace auv::recon::evaluate
