#include "auv/recon/evaluate/evaluator.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include <open3d/geometry/PointCloud.h>
#include <open3d/geometry/TriangleMesh.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgcodecs.hpp>

#include "auv/recon/common/progress.h"
#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/staged_output.h"
#include "auv/recon/evaluate/alignment.h"
#include "auv/recon/evaluate/change_evaluation.h"
#include "auv/recon/evaluate/ground_truth.h"
#include "auv/recon/evaluate/image_matching.h"
#include "auv/recon/evaluate/image_metrics.h"
#include "auv/recon/evaluate/surface_metrics.h"
#include "auv/recon/evaluate/survey_truth.h"
#include "auv/recon/evaluate/well_imaged_region.h"
#include "auv/recon/scene/colmap_text.h"
#include "auv/recon/scene/mesh_io.h"
#include "auv/recon/scene/ply.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace auv::recon::evaluate {
namespace {

constexpr const char* kStage = "evaluate";

/// JSON has no infinity: such figures are written as null.
json number(double value) { return std::isfinite(value) ? json(value) : json(nullptr); }

json scoresJson(const SurfaceScores& s) {
  json j;
  j["points_evaluated"] = s.points_evaluated;
  j["points_outside_region"] = s.points_outside;
  j["truth_samples"] = s.samples_evaluated;
  j["accuracy_m"] = {{"mean", number(s.mean_accuracy_m)}, {"median", number(s.median_accuracy_m)}};
  j["completeness_m"] = {{"mean", number(s.mean_completeness_m)},
                         {"median", number(s.median_completeness_m)}};
  j["thresholds"] = json::array();
  for (const ThresholdScore& t : s.scores) {
    j["thresholds"].push_back({{"threshold_m", t.threshold_m},
                               {"precision", t.precision},
                               {"recall", t.recall},
                               {"fscore", t.fscore}});
  }
  return j;
}

json similarityJson(const Similarity& s) {
  json rotation = json::array();
  for (int r = 0; r < 3; ++r)
    rotation.push_back({s.rotation(r, 0), s.rotation(r, 1), s.rotation(r, 2)});
  return {{"scale", s.scale},
          {"rotation", rotation},
          {"translation", {s.translation.x(), s.translation.y(), s.translation.z()}}};
}

std::string cameraOfName(const std::string& name) {
  const size_t slash = name.find('/');
  return slash == std::string::npos ? std::string() : name.substr(0, slash);
}

std::vector<Eigen::Vector3d> transformed(const std::vector<Eigen::Vector3d>& points,
                                         const Similarity& s) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(points.size());
  for (const auto& p : points) out.push_back(s.apply(p));
  return out;
}

void check(bool condition, const std::string& message) {
  if (!condition) throw StageError(kStage, message);
}

}  // namespace

std::vector<double> EvaluateOptions::thresholds() const {
  std::vector<double> values;
  std::stringstream in(thresholds_m);
  std::string item;
  while (std::getline(in, item, ',')) {
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !(v > 0) || !std::isfinite(v)) {
      detail::throwOptionError("thresholds_m", thresholds_m,
                               "expected positive distances in m, comma-separated");
    }
    values.push_back(v);
  }
  if (values.empty()) {
    detail::throwOptionError("thresholds_m", thresholds_m, "expected at least one distance");
  }
  std::sort(values.begin(), values.end());
  return values;
}

void EvaluateOptions::check() const {
  thresholds();
  AUV_RECON_CHECK_OPTION(sample_spacing_m >= 0.001 && sample_spacing_m <= 1.0, sample_spacing_m,
                         "must be in [0.001, 1] m");
  AUV_RECON_CHECK_OPTION(psnr_views >= 0, psnr_views, "must be >= 0");
  AUV_RECON_CHECK_OPTION(max_range_m >= 0, max_range_m, "must be >= 0 m (0 = water visibility)");
  WellImagedOptions region;
  region.min_views = min_views;
  region.max_range_m = max_range_m > 0 ? max_range_m : kDefaultWellImagedRangeM;
  region.max_incidence_deg = max_incidence_deg;
  region.check();
  AlignmentOptions alignment;
  alignment.axis_length_m = axis_length_m;
  alignment.inlier_sigmas = inlier_sigmas;
  alignment.min_inlier_m = min_inlier_m;
  alignment.check();
  change.check();
}

fs::path recordedRun(const Survey& survey, const std::string& key) {
  const fs::path file = survey.root() / "simulation.json";
  if (!fs::exists(file)) return {};
  try {
    std::ifstream in(file);
    const json j = json::parse(in);
    if (!j.contains(key)) return {};
    fs::path run = j.at(key).get<std::string>();
    return run.is_relative() ? survey.root() / run : run;
  } catch (const std::exception& e) {
    throw StageError(kStage, file.string() + ": " + e.what());
  }
}

fs::path recordedGroundTruth(const Survey& survey) {
  return recordedRun(survey, "ground_truth_run");
}

json evaluateSurvey(const Survey& survey, const fs::path& ground_truth_run,
                    const EvaluateOptions& options, const TexturedModelRenderer& renderer) {
  options.check();
  const auto started = std::chrono::steady_clock::now();
  const std::vector<double> thresholds = options.thresholds();

  // The sparse model first: it carries the poses (a survey without it needs sfm, whatever
  // the truth).
  Survey::requireExists(survey.sparse() / "images.txt", kStage, "sfm");
  const GroundTruth truth = GroundTruth::load(ground_truth_run);
  Progress progress("evaluate", "steps", 7);
  // 1.-2. Images -> ground-truth frames; similarity from the camera poses; pose errors.
  const SurveyAlignment aligned = alignSurveyToTruth(survey, truth, options);
  const scene::Reconstruction& sparse = aligned.sparse;
  const auto& sources = aligned.sources;
  const ImageMatching& matching = aligned.matching;
  const std::vector<PosePair>& pairs = aligned.pairs;
  const AlignmentResult& alignment = aligned.alignment;
  const Similarity& sim = alignment.similarity;
  const PoseErrors& errors = aligned.errors;
  progress.advance();

  json result;
  result["format"] = "auv-recon-evaluation 1";
  result["ground_truth_run"] = ground_truth_run.string();
  result["world_mesh"] = truth.meshFile().string();

  size_t keyframes = 0;
  for (const auto& [camera, list] : sources) keyframes += list.size();
  json per_camera = json::object();
  for (const auto& [camera, list] : sources) per_camera[camera]["keyframes"] = list.size();
  for (const auto& [id, image] : sparse.images) {
    json& c = per_camera[cameraOfName(image.name)];
    c["registered"] = c.value("registered", 0) + 1;
  }
  std::map<std::string, std::vector<double>> position_by_camera;
  for (size_t i = 0; i < pairs.size(); ++i) {
    position_by_camera[cameraOfName(pairs[i].name)].push_back(errors.position_m[i]);
  }
  for (auto& [camera, values] : position_by_camera) {
    per_camera[camera]["matched"] = values.size();
    per_camera[camera]["median_position_error_m"] = median(values);
  }
  json unmatched = json::array();
  for (size_t i = 0; i < std::min<size_t>(20, matching.unmatched.size()); ++i) {
    unmatched.push_back(matching.unmatched[i]);
  }
  result["images"] = {{"keyframes", keyframes},
                      {"registered", sparse.images.size()},
                      {"matched_to_truth", matching.matched.size()},
                      {"unmatched", matching.unmatched.size()},
                      {"unmatched_examples", unmatched},
                      {"per_camera", per_camera}};
  json similarity = similarityJson(sim);
  similarity["inliers"] = alignment.num_inliers;
  similarity["images"] = pairs.size();
  similarity["robust_sigma_m"] = alignment.robust_sigma_m;
  similarity["axis_length_m"] = options.axis_length_m;
  similarity["method"] =
      "Umeyama similarity on camera centres and axis points, LMedS outlier rejection";
  result["alignment"] = similarity;
  result["camera_error"] = {{"position_m",
                             {{"mean", errors.mean_position_m},
                              {"median", errors.median_position_m},
                              {"rms", errors.rms_position_m},
                              {"max", errors.max_position_m}}},
                            {"rotation_deg",
                             {{"mean", errors.mean_rotation_deg},
                              {"median", errors.median_rotation_deg},
                              {"max", errors.max_rotation_deg}}}};

  // 3. The well-imaged region: seen by min_views keyframes (their true poses), within range.
  const std::vector<View> views = keyframeViews(truth, aligned);
  const auto mesh = truth.worldMesh();
  const WellImagedSamples region = wellImagedRegion(truth, views, options);
  const SurfaceSamples& samples = region.samples;
  const std::vector<bool>& well_imaged = region.well_imaged;
  const size_t region_size = region.count;
  check(region_size > 0, "no part of the true surface is seen by " +
                             std::to_string(options.min_views) + " keyframes within " +
                             std::to_string(region.max_range_m) + " m");
  const double sample_area = options.sample_spacing_m * options.sample_spacing_m;
  result["region"] = {
      {"definition",
       "true surface seen by >= min_views keyframes (true poses and lenses): inside the image, "
       "within max_range_m, not occluded, at most max_incidence_deg from the normal"},
      {"min_views", options.min_views},
      {"max_range_m", region.max_range_m},
      {"max_incidence_deg", options.max_incidence_deg},
      {"keyframe_views", views.size()},
      {"sample_spacing_m", options.sample_spacing_m},
      {"samples_near_cameras", samples.size()},
      {"samples_well_imaged", region_size},
      {"area_well_imaged_m2", static_cast<double>(region_size) * sample_area}};
  progress.advance();

  // 4. Surfaces: the sparse cloud, the dense cloud and the mesh, whichever exist.
  json surfaces = json::object();
  {
    std::vector<Eigen::Vector3d> points;
    for (const auto& [id, point] : sparse.points) points.push_back(point.xyz);
    if (!points.empty()) {
      surfaces["sparse"] = scoresJson(scoreSurface(*mesh, samples.points, well_imaged,
                                                   transformed(points, sim), nullptr, thresholds));
      surfaces["sparse"]["file"] = (survey.sparse() / "points3D.txt").string();
    }
  }
  progress.advance();
  const fs::path fused = survey.dense() / "fused.ply";
  if (fs::exists(fused)) {
    open3d::geometry::PointCloud cloud;
    check(scene::readPointCloud(fused, cloud), fused.string() + ": unreadable point cloud");
    check(!cloud.points_.empty(), fused.string() + ": empty point cloud");
    surfaces["dense"] = scoresJson(scoreSurface(
        *mesh, samples.points, well_imaged, transformed(cloud.points_, sim), nullptr, thresholds));
    surfaces["dense"]["file"] = fused.string();
  }
  progress.advance();
  const fs::path mesh_file = survey.mesh() / "mesh.ply";
  if (fs::exists(mesh_file)) {
    open3d::geometry::TriangleMesh reconstructed;
    check(scene::readTriangleMesh(mesh_file, reconstructed),
          mesh_file.string() + ": unreadable mesh");
    check(!reconstructed.triangles_.empty(), mesh_file.string() + ": mesh without triangles");
    reconstructed.Transform(sim.matrix());
    const SurfaceSamples mesh_samples = sampleSurface(reconstructed, options.sample_spacing_m,
                                                      static_cast<uint64_t>(options.seed) + 1);
    surfaces["mesh"] = scoresJson(scoreSurface(*mesh, samples.points, well_imaged,
                                               mesh_samples.points, &reconstructed, thresholds));
    surfaces["mesh"]["file"] = mesh_file.string();
    surfaces["mesh"]["triangles"] = reconstructed.triangles_.size();
  }
  result["surfaces"] = surfaces;
  progress.advance();

  // 5. Texture: the textured model at held-out frames against the simulator's frames (as
  //    filmed, through water) and against the world's true texture at the same views.
  json texture = {{"status", "not evaluated"}};
  const fs::path model = survey.textured() / "model.obj";
  if (!fs::exists(model)) {
    texture["status"] = "no textured model (" + model.string() + ")";
  } else if (!renderer) {
    texture["status"] = "no renderer of textured models in this build";
  } else if (options.psnr_views > 0) {
    // Keyframes per video, held-out frames midway between them.
    std::map<std::string, std::vector<int64_t>> keyframes_of;  // video stem -> frames
    std::map<std::string, std::string> camera_of;              // video stem -> camera
    for (const auto& [camera, list] : sources) {
      for (const KeyframeSource& s : list) {
        const std::string stem = fs::path(s.video).stem().string();
        keyframes_of[stem].push_back(s.frame);
        camera_of[stem] = camera;
      }
    }
    std::map<std::string, int64_t> frame_count;
    std::map<std::string, std::string> video_file;
    for (const auto& [key, frame] : truth.frames()) {
      const std::string stem = fs::path(frame.video).stem().string();
      frame_count[stem] = std::max(frame_count[stem], frame.frame + 1);
      video_file[stem] = frame.video;
    }
    const size_t per_video = std::max<size_t>(
        1, static_cast<size_t>(options.psnr_views) / std::max<size_t>(1, keyframes_of.size()));
    std::vector<double> raw, gain, true_raw, true_gain, true_delta_e;
    const fs::path true_texture_run = options.true_texture_run.empty()
                                          ? recordedRun(survey, "true_texture_run")
                                          : fs::path(options.true_texture_run);
    texture["true_texture_run"] = true_texture_run.string();
    json frames = json::array();
    json missing_videos = json::array();  // deleted after the reconstruction: the rest is scored
    for (const auto& [stem, list] : keyframes_of) {
      if (!frame_count.count(stem)) continue;
      const std::vector<int64_t> held = heldOutFrames(list, frame_count[stem], per_video);
      if (held.empty()) continue;
      fs::path video = survey.recordings() / camera_of[stem] / video_file[stem];
      if (!fs::exists(video))
        video = ground_truth_run / "vehicle" / "recordings" / camera_of[stem] / video_file[stem];
      if (!fs::exists(video)) {
        missing_videos.push_back(video.string());
        continue;
      }
      const std::vector<cv::Mat> references = readVideoFrames(video, held);
      // The same frames rendered in clear water (the true texture), when there is such a run.
      std::vector<cv::Mat> true_frames;
      if (!true_texture_run.empty()) {
        const fs::path clear =
            true_texture_run / "vehicle" / "recordings" / camera_of[stem] / video_file[stem];
        if (!fs::exists(clear)) {
          throw StageError(kStage, clear.string() + ": missing from the true-texture run (" +
                                       true_texture_run.string() + ")");
        }
        true_frames = readVideoFrames(clear, held);
      }
      for (size_t i = 0; i < held.size(); ++i) {
        const GroundTruthFrame* frame = truth.find(frameKey(stem, held[i]));
        if (!frame) continue;
        const scene::Camera& lens = truth.cameras().at(frame->image.camera_id);
        scene::Camera pinhole = scene::Camera::pinhole(lens.id, lens.width, lens.height, lens.fx,
                                                       lens.fy, lens.cx, lens.cy);
        cv::Mat K, distortion, reference;
        cv::eigen2cv(lens.K(), K);
        distortion = cv::Mat(lens.distortion, true).reshape(1, 1);
        cv::undistort(references[i], reference, K, distortion, K);
        // The truth's pose in the model's frame: x_camera ~ R_t (s R x + t) + t_t.
        const Eigen::Matrix3d R = frame->image.rotation() * sim.rotation;
        const Eigen::Vector3d t =
            (frame->image.rotation() * sim.translation + frame->image.t_cw) / sim.scale;
        cv::Mat image, mask;
        if (!renderer(model, pinhole, R, t, image, mask)) continue;
        const PsnrResult p = psnr(reference, image, mask);
        if (p.pixels == 0) continue;
        raw.push_back(p.psnr_db);
        gain.push_back(p.psnr_gain_db);
        json entry = {{"frame", frameKey(stem, held[i])},
                      {"psnr_db", number(p.psnr_db)},
                      {"psnr_gain_offset_db", number(p.psnr_gain_db)},
                      {"coverage", static_cast<double>(p.pixels) / reference.total()}};
        cv::Mat true_image;
        if (i < true_frames.size() && !true_frames[i].empty()) {
          cv::undistort(true_frames[i], true_image, K, distortion, K);
          const PsnrResult q = psnr(true_image, image, mask);
          if (q.pixels > 0) {
            true_raw.push_back(q.psnr_db);
            true_gain.push_back(q.psnr_gain_db);
            entry["psnr_true_texture_db"] = number(q.psnr_db);
            entry["psnr_true_texture_gain_offset_db"] = number(q.psnr_gain_db);
            const DeltaEResult e = deltaE2000(true_image, image, mask);
            true_delta_e.push_back(e.mean);
            entry["delta_e_2000_true_texture"] = number(e.mean);
          }
        }
        if (options.write_views) {
          cv::Mat model_view = cv::Mat::zeros(image.size(), image.type());
          image.copyTo(model_view, mask);
          if (true_image.size() != image.size())
            true_image = cv::Mat::zeros(image.size(), image.type());
          cv::Mat side_by_side;
          cv::hconcat(std::vector<cv::Mat>{reference, model_view, true_image}, side_by_side);
          fs::create_directories(survey.root() / "evaluation" / "views");
          const fs::path file =
              survey.root() / "evaluation" / "views" / (frameKey(stem, held[i]) + ".png");
          if (!cv::imwrite(file.string(), side_by_side)) {
            throw StageError(kStage, file.string() + ": cannot write");
          }
        }
        frames.push_back(entry);
      }
    }
    texture["status"] = !raw.empty()              ? "evaluated"
                        : !missing_videos.empty() ? "the filmed videos are gone"
                                                  : "no held-out frame could be rendered";
    texture["frames"] = frames;
    if (!missing_videos.empty()) texture["missing_videos"] = missing_videos;
    if (!raw.empty()) {
      texture["median_psnr_db"] = number(median(raw));
      texture["median_psnr_gain_offset_db"] = number(median(gain));
    }
    if (!true_raw.empty()) {
      texture["median_psnr_true_texture_db"] = number(median(true_raw));
      texture["median_psnr_true_texture_gain_offset_db"] = number(median(true_gain));
      texture["median_delta_e_2000_true_texture"] = number(median(true_delta_e));
    }
  }
  result["texture"] = texture;

  if (options.write_clouds) {
    scene::PlyData ply;
    for (size_t i = 0; i < samples.size(); ++i) {
      ply.positions.push_back(samples.points[i]);
      ply.colors.push_back(well_imaged[i] ? Eigen::Matrix<uint8_t, 3, 1>(40, 200, 60)
                                          : Eigen::Matrix<uint8_t, 3, 1>(150, 150, 150));
    }
    fs::create_directories(survey.root() / "evaluation");
    scene::writePly(survey.root() / "evaluation" / "region.ply", ply);
  }

  // 6. The change since an earlier survey, when it was compared and the truth knows it.
  result["change"] = evaluateChange(survey, ground_truth_run, region, options);
  progress.advance();

  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  result["seconds"] = seconds;
  progress.advance();
  progress.finish();
  writeFileAtomically(survey.root() / "evaluation.json", result.dump(2) + "\n");

  json section = {{"ground_truth_run", ground_truth_run.string()},
                  {"images_matched", matching.matched.size()},
                  {"camera_position_error_median_m", errors.median_position_m},
                  {"region_area_m2", result["region"]["area_well_imaged_m2"]},
                  {"seconds", seconds},
                  {"options",
                   {{"thresholds_m", options.thresholds_m},
                    {"sample_spacing_m", options.sample_spacing_m},
                    {"min_views", options.min_views},
                    {"max_range_m", region.max_range_m},
                    {"max_incidence_deg", options.max_incidence_deg},
                    {"axis_length_m", options.axis_length_m}}}};
  for (const auto& [name, s] : surfaces.items()) {
    for (const auto& t : s["thresholds"]) {
      std::ostringstream key;
      key << "fscore_" << name << "_" << std::lround(t["threshold_m"].get<double>() * 100) << "cm";
      section[key.str()] = t["fscore"];
    }
  }
  const json& change = result["change"];
  section["change_status"] = change["status"];
  if (change["status"] == "evaluated") {
    section["change_recall"] = change["regions_scored"]["recall_measured"];
    section["change_recall_all"] = change["regions_scored"]["recall_all"];
    section["change_precision"] = change["clusters_scored"]["precision"];
    section["change_false_area_m2"] = change["stable"]["false_area_m2"];
    section["change_false_fraction"] = change["stable"]["false_fraction"];
    section["change_survey_1_camera_error_median_m"] =
        change["survey_1"]["alignment"]["camera_position_error_median_m"];
    const json& appearance = change["appearance"];
    section["change_appearance_status"] = appearance["status"];
    if (appearance["status"] == "evaluated") {
      section["change_appearance_recall"] = appearance["regions_scored"]["recall_measured"];
      section["change_appearance_precision"] = appearance["clusters_scored"]["precision"];
      section["change_appearance_false_area_m2"] = appearance["stable"]["false_cluster_area_m2"];
    }
  }
  updateReport(survey.report(), kStage, section);
  return result;
}

}  // namespace auv::recon::evaluate
