#include "auv/recon/sfm/sfm_stage.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "auv/recon/calibration/calibration.h"
#include "auv/recon/common/option_set.h"
#include "auv/recon/common/progress.h"
#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/staged_output.h"
#include "auv/recon/common/threads.h"
#include "auv/recon/features/feature_store.h"
#include "auv/recon/features/match_store.h"
#include "auv/recon/scene/colmap_text.h"
#include "auv/recon/scene/ply.h"
#include "auv/recon/sfm/undistorted_model.h"

namespace auv::recon::sfm {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {
constexpr const char* kStage = "sfm";

double since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// corrected/<camera>.yaml: the pinhole intrinsics of the undistorted images.
scene::Camera readCorrectedCamera(const fs::path& file, uint32_t id) {
  if (!fs::exists(file)) {
    throw StageError(kStage, "calibration of the corrected images not found: " + file.string() +
                                 " (run `auv recon correct` first)");
  }
  return calibration::readUndistortedCamera(file, id, kStage);
}
}  // namespace

void SfmStageOptions::check() const {
  mapper.check();
  lossFunctionFromName(loss);  // throws naming the value
  AUV_RECON_CHECK_OPTION(min_registered_ratio >= 0 && min_registered_ratio <= 1,
                         min_registered_ratio, "must be in [0, 1]");
  AUV_RECON_CHECK_OPTION(threads >= 0, threads, "must be >= 0 (0: the CPUs the process may use)");
}

MapperOptions SfmStageOptions::mapperOptions() const {
  MapperOptions m = mapper;
  m.ba.loss = lossFunctionFromName(loss);
  m.ba.num_threads = threads > 0 ? threads : defaultThreadCount();
  return m;
}

void SfmStageOptions::bind(OptionSet& set) {
  MapperOptions& m = mapper;
  set.add("init_min_inliers", &m.init_min_inliers, "essential inliers of the initial pair");
  set.add("init_min_tri_angle", &m.init_min_tri_angle_deg,
          "deg: median triangulation angle of the initial pair (halved when none passes)");
  set.add("init_max_homography_ratio", &m.init_max_homography_ratio,
          "homography / essential inliers above this: planar pair, tried last");
  set.add("init_max_pairs", &m.init_max_pairs, "candidate initial pairs tried");
  set.add("abs_pose_min_inliers", &m.abs_pose_min_inliers, "2D-3D inliers to register a view");
  set.add("abs_pose_min_inlier_ratio", &m.abs_pose_min_inlier_ratio,
          "inliers / 2D-3D correspondences to register a view");
  set.add("min_tri_angle", &m.min_tri_angle_deg, "deg: smallest triangulation angle of a point");
  set.add("ignore_two_view_tracks", &m.ignore_two_view_tracks,
          "leave tracks of only two images untriangulated (except the initial pair's)");
  set.add("max_reprojection_error", &m.max_reprojection_error_px,
          "px: observations beyond are outliers (also the bound of AC-RANSAC's threshold)");
  set.add("local_ba_images", &m.local_ba_images, "images refined by a local bundle adjustment");
  set.add("global_ba_growth", &m.global_ba_growth,
          "global bundle adjustment when the model grew by this fraction");
  set.add("loss", &loss, "bundle adjustment loss: trivial, huber, cauchy, soft_l1");
  set.add("loss_scale", &m.ba.loss_scale_px, "px: scale of the robust loss");
  set.add("min_registered_ratio", &min_registered_ratio,
          "below this fraction registered the model is partial: written to sparse-partial/ and "
          "the stage fails (exit 1), unless --accept-partial");
  set.add("accept_partial", &accept_partial,
          "a partial model goes to sparse/ and the stage succeeds with a warning");
  set.add("navigation", &navigation,
          "TUM trajectory (e.g. <run>/ground_truth/navigation.tum): metric scale and gravity "
          "(default: the survey's navigation.tum, if any)");
  set.add("threads", &threads, "Ceres threads (0: OMP_NUM_THREADS, else the CPUs allowed)");
  set.add("refine_focal_length", &m.refine_focal_length,
          "self-calibrate the focal length of cameras that only have a prior (import)");
  set.add("refine_principal_point", &m.refine_principal_point,
          "and their principal point (weakly observed: off by default)");
  set.add("refine_radial_distortion", &m.refine_radial_distortion,
          "and their radial distortion k1, k2 (OpenCV model)");
  set.add("refine_tangential_distortion", &m.refine_tangential_distortion,
          "and their tangential distortion p1, p2 (weakly observed: off by default)");
  set.add("max_focal_ratio", &m.max_focal_ratio,
          "a refined focal beyond this factor of the prior is reset to the prior and flagged");
}

SfmInput readSfmInput(const Survey& survey) {
  SfmInput input;
  Survey::requireExists(survey.corrected(), kStage, "correct");
  const std::vector<std::string> cameras = Survey::cameraFolders(survey.corrected(), kStage);
  std::map<std::string, uint32_t> camera_ids;
  for (const std::string& name : cameras) {
    const uint32_t id = static_cast<uint32_t>(camera_ids.size() + 1);
    camera_ids[name] = id;
    const fs::path yaml = survey.corrected() / (name + ".yaml");
    input.cameras[id] = readCorrectedCamera(yaml, id);
    if (!calibration::readCalibration(yaml, kStage).prior_source.empty()) {
      input.uncalibrated.insert(id);
    }
  }
  const fs::path features_folder = survey.root() / "features";
  const features::FeatureStore store(features_folder);
  std::map<std::string, uint32_t> image_ids;
  for (const features::FeatureIndexEntry& entry : store.images()) {
    auto camera = camera_ids.find(entry.camera);
    if (camera == camera_ids.end()) {
      throw StageError(kStage, "features/index.csv: image " + entry.image + " of camera '" +
                                   entry.camera + "', which has no folder in " +
                                   survey.corrected().string());
    }
    const scene::Camera& intrinsics = input.cameras.at(camera->second);
    if (entry.width != intrinsics.width || entry.height != intrinsics.height) {
      throw StageError(
          kStage, "features of " + entry.image + " are of a " + std::to_string(entry.width) + "x" +
                      std::to_string(entry.height) + " image, but " + entry.camera + ".yaml says " +
                      std::to_string(intrinsics.width) + "x" + std::to_string(intrinsics.height));
    }
    View view;
    view.id = static_cast<uint32_t>(input.views.size() + 1);
    view.camera_id = camera->second;
    view.name = entry.image;
    view.keypoints = store.read(entry.image).positions();
    image_ids[entry.image] = view.id;
    input.views.push_back(std::move(view));
  }
  const fs::path pairs_file = features::verifiedPairsFile(features_folder);
  if (!fs::exists(pairs_file)) {
    throw StageError(kStage, "verified matches not found: " + pairs_file.string() +
                                 " (run `auv recon match` first)");
  }
  for (const features::VerifiedPair& verified : features::readVerifiedPairs(pairs_file)) {
    auto a = image_ids.find(verified.image1), b = image_ids.find(verified.image2);
    if (a == image_ids.end() || b == image_ids.end()) {
      throw StageError(kStage, pairs_file.string() + ": pair (" + verified.image1 + ", " +
                                   verified.image2 + ") names an image not in features/");
    }
    ViewPair pair;
    pair.image_a = a->second;
    pair.image_b = b->second;
    pair.matches.assign(verified.inliers.begin(), verified.inliers.end());
    pair.homography_inliers = verified.homography_inliers;
    if (verified.kind == features::GeometryKind::ESSENTIAL) pair.essential = verified.model;
    input.pairs.push_back(std::move(pair));
  }
  try {
    input.check();
  } catch (const std::invalid_argument& e) {
    throw StageError(kStage, pairs_file.string() + ": " + e.what());
  }
  return input;
}

void writeSparseModel(const scene::Reconstruction& rec, const fs::path& folder) {
  scene::writeColmapText(rec, folder);
  scene::PlyData points;
  for (const auto& [id, point] : rec.points) {
    points.positions.push_back(point.xyz);
    points.colors.push_back(point.rgb);
  }
  scene::writePly(folder / "points.ply", points);
  // Camera glyphs: frusta a tenth of the model's median camera spacing deep, one colour per
  // physical camera.
  std::vector<double> spacing;
  const scene::Image* previous = nullptr;
  for (const auto& [id, image] : rec.images) {
    if (previous) spacing.push_back((image.center() - previous->center()).norm());
    previous = &image;
  }
  double depth = 0.1;
  if (!spacing.empty()) {
    std::nth_element(spacing.begin(), spacing.begin() + spacing.size() / 2, spacing.end());
    depth = std::max(spacing[spacing.size() / 2], 1e-6);
  }
  const Eigen::Matrix<uint8_t, 3, 1> palette[] = {
      {230, 60, 60}, {60, 200, 60}, {60, 90, 230}, {230, 200, 40}, {200, 60, 200}};
  scene::PlyData glyphs;
  for (const auto& [id, image] : rec.images) {
    const scene::Camera& camera = rec.cameraOf(image);
    scene::CameraGlyph glyph;
    glyph.center = image.center();
    glyph.rotation_cw = image.rotation();
    glyph.depth = depth;
    glyph.half_width = depth * camera.width / (2 * camera.fx);
    glyph.half_height = depth * camera.height / (2 * camera.fy);
    glyph.color = palette[(camera.id - 1) % 5];
    scene::appendCameraGlyph(glyph, glyphs);
  }
  scene::writePly(folder / "cameras.ply", glyphs);
}

SfmStageResult runSfmStage(const Survey& survey, const SfmStageOptions& options) {
  options.check();
  const auto start = Clock::now();
  SfmStageResult summary;
  // Keypoint colours for the points, read with the keypoints.
  SfmInput input = readSfmInput(survey);
  std::map<uint32_t, std::vector<std::array<uint8_t, 3>>> colors;
  {
    const features::FeatureStore store(survey.root() / "features");
    for (const View& view : input.views) {
      std::vector<std::array<uint8_t, 3>>& c = colors[view.id];
      for (const auto& k : store.read(view.name).keypoints) c.push_back(k.rgb);
    }
  }
  // The vehicle's navigation: the option, else the survey's navigation.tum (as match reads
  // it), so a simulated or logged survey comes out metric, in its navigation frame.
  fs::path navigation = options.navigation;
  if (navigation.empty() && fs::exists(survey.root() / "navigation.tum"))
    navigation = survey.root() / "navigation.tum";
  std::vector<TimedPosition> trajectory;
  std::map<std::string, double> times;
  if (!navigation.empty()) {
    try {
      trajectory = readTumTrajectory(navigation);
      times =
          readKeyframeTimes(survey.keyframes(), Survey::cameraFolders(survey.corrected(), kStage));
    } catch (const std::runtime_error& e) {
      throw StageError(kStage, std::string("navigation: ") + e.what());
    }
  }
  summary.seconds_reading = since(start);
  summary.images_total = input.views.size();
  summary.cameras = input.cameras.size();

  std::map<uint32_t, std::string> names;
  for (const View& view : input.views) names[view.id] = view.name;
  const std::map<uint32_t, scene::Camera> priors = input.cameras;
  const std::set<uint32_t> uncalibrated = input.uncalibrated;
  const std::vector<std::string> camera_names = Survey::cameraFolders(survey.corrected(), kStage);
  MapperResult result;
  {
    Progress progress("sfm", "images", input.views.size());
    IncrementalMapper mapper(std::move(input), options.mapperOptions());
    result = mapper.run(&progress, [&](const std::string& line) { progress.message(line); });
  }
  if (result.status != MapperStatus::SUCCESS) throw StageError(kStage, result.message);
  scene::Reconstruction& rec = result.reconstruction;
  const size_t registered = rec.images.size();
  summary.partial = registered < options.min_registered_ratio * summary.images_total;
  std::ostringstream partial_message;
  if (summary.partial) {
    partial_message << "partial result: " << registered << " of " << summary.images_total
                    << " images registered (min_registered_ratio " << options.min_registered_ratio
                    << ")";
    size_t listed = 0;
    for (const auto& [id, why] : result.unregistered_reasons) {
      if (listed++ == 3) {
        partial_message << "; ... (all in report.json)";
        break;
      }
      partial_message << "; " << names.at(id) << ": " << why;
    }
  }
  for (auto& [id, point] : rec.points) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const auto& e : point.track) {
      const auto& rgb = colors.at(e.image_id).at(e.point2d_idx);
      sum += Eigen::Vector3d(rgb[0], rgb[1], rgb[2]);
    }
    sum /= std::max<size_t>(point.track.size(), 1);
    point.rgb = sum.array().round().cast<uint8_t>();
  }
  if (!navigation.empty()) {
    summary.navigation = alignToNavigation(rec, times, trajectory);
    if (!summary.navigation.applied) {
      std::cerr << "sfm: navigation alignment not applied: " << summary.navigation.reason << "\n";
    }
  }

  const auto writing = Clock::now();
  // A partial model does not replace a whole one unless accepted: the stages after sfm read
  // sparse/, and `auv recon run` would go on with a model the user did not choose.
  const fs::path model_folder = summary.partial && !options.accept_partial
                                    ? survey.root() / "sparse-partial"
                                    : survey.sparse();
  StagedOutput staged(model_folder);
  writeSparseModel(rec, staged.path());
  // The self-calibrated cameras' estimates, as calibration files.
  nlohmann::json intrinsics = nlohmann::json::object();
  for (uint32_t id : uncalibrated) {
    const scene::Camera& camera = rec.cameras.at(id);
    const std::string& name = camera_names.at(id - 1);
    const calibration::CameraCalibration estimate = calibration::calibrationOf(camera);
    calibration::writeCalibration(staged.path() / (name + ".yaml"), estimate,
                                  calibration::CalibrationOptions());
    const auto reset = result.intrinsics_reset.find(id);
    intrinsics[name] = {
        {"prior_fx", priors.at(id).fx},
        {"fx", camera.fx},
        {"fy", camera.fy},
        {"cx", camera.cx},
        {"cy", camera.cy},
        {"distortion",
         camera.distortion.empty() ? std::vector<double>{0, 0, 0, 0} : camera.distortion},
        {"focal_change_percent", 100.0 * (camera.fx / priors.at(id).fx - 1.0)},
        {"refined", options.mapper.refine_focal_length && reset == result.intrinsics_reset.end()},
        {"reset", reset == result.intrinsics_reset.end() ? "" : reset->second}};
    summary.self_calibrated[name] = camera.fx;
    if (reset != result.intrinsics_reset.end()) {
      summary.warnings.push_back("camera '" + name + "': " + reset->second);
    }
  }
  // Dense matching and texturing need pinhole images: when a lens distortion was estimated,
  // the undistorted workspace is written before anything is committed, so a failure leaves
  // both folders of the earlier run as they were.
  const bool lens_distortion = std::any_of(rec.cameras.begin(), rec.cameras.end(),
                                           [](const auto& c) { return c.second.hasDistortion(); });
  std::optional<StagedOutput> undistorted;
  if (model_folder == survey.sparse() && lens_distortion) {
    undistorted.emplace(survey.undistorted());
    writeUndistortedWorkspace(rec, survey.corrected(), undistorted->path());
  }
  staged.commit();
  if (undistorted) {
    undistorted->commit();
  } else if (model_folder == survey.sparse()) {
    fs::remove_all(survey.undistorted());  // an earlier run's, for another model
  }
  summary.seconds_writing = since(writing);

  summary.images_registered = registered;
  summary.points = rec.points.size();
  summary.observations = rec.numObservations();
  summary.mean_track_length = rec.meanTrackLength();
  summary.mean_reprojection_error_px = rec.meanReprojectionError();
  summary.seconds = since(start);

  const MapperTimings& t = result.timings;
  nlohmann::json section = {
      {"images_total", summary.images_total},
      {"images_registered", summary.images_registered},
      {"cameras", summary.cameras},
      {"points", summary.points},
      {"observations", summary.observations},
      {"mean_track_length", summary.mean_track_length},
      {"mean_reprojection_error_px", summary.mean_reprojection_error_px},
      {"tracks", result.tracks.tracks},
      {"conflicting_matches", result.tracks.conflicting_matches},
      {"local_bundle_adjustments", result.local_bas},
      {"global_bundle_adjustments", result.global_bas},
      {"seconds", summary.seconds},
      {"seconds_per_substage",
       {{"reading", summary.seconds_reading},
        {"tracks", t.tracks},
        {"initial_pair", t.initial_pair},
        {"registration", t.registration},
        {"triangulation", t.triangulation},
        {"local_ba", t.local_ba},
        {"global_ba", t.global_ba},
        {"filtering", t.filtering},
        {"writing", summary.seconds_writing}}},
      {"options",
       {{"init_min_inliers", options.mapper.init_min_inliers},
        {"init_min_tri_angle_deg", options.mapper.init_min_tri_angle_deg},
        {"abs_pose_min_inliers", options.mapper.abs_pose_min_inliers},
        {"min_tri_angle_deg", options.mapper.min_tri_angle_deg},
        {"max_reprojection_error_px", options.mapper.max_reprojection_error_px},
        {"ignore_two_view_tracks", options.mapper.ignore_two_view_tracks},
        {"loss", options.loss},
        {"loss_scale_px", options.mapper.ba.loss_scale_px},
        {"navigation", navigation.string()}}}};
  std::vector<std::string> unregistered;
  for (uint32_t id : result.unregistered) unregistered.push_back(names.at(id));
  section["unregistered_images"] = unregistered;
  section["self_calibration"] = intrinsics;
  section["partial"] = summary.partial;
  section["model_folder"] = model_folder.string();
  nlohmann::json reasons = nlohmann::json::object();
  for (const auto& [id, why] : result.unregistered_reasons) reasons[names.at(id)] = why;
  section["unregistered_reasons"] = reasons;
  if (!navigation.empty()) {
    section["navigation"] = {{"applied", summary.navigation.applied},
                             {"images", summary.navigation.images},
                             {"scale", summary.navigation.similarity.scale},
                             {"rms_m", summary.navigation.rms_m},
                             {"reason", summary.navigation.reason}};
  }
  updateReport(survey.report(), kStage, section);
  summary.mapper = std::move(result);
  if (summary.partial) {
    if (!options.accept_partial) {
      throw PartialResult(kStage, partial_message.str() + "; the model is in " +
                                      model_folder.string() + ", " + survey.sparse().string() +
                                      " is unchanged (--accept-partial takes it)");
    }
    summary.warnings.push_back(partial_message.str() + ": accepted (--accept-partial)");
  }
  return summary;
}

StageReport SfmStage::runWith(const Survey& survey, const SfmStageOptions& options) const {
  const SfmStageResult s = runSfmStage(survey, options);
  std::ostringstream line;
  line << "sfm: " << s.images_registered << " of " << s.images_total << " images registered, "
       << s.points << " points, mean track length " << s.mean_track_length
       << ", mean reprojection error " << s.mean_reprojection_error_px << " px";
  if (s.navigation.applied) {
    line << ", aligned to the navigation (" << s.navigation.images << " images, rms "
         << s.navigation.rms_m << " m)";
  }
  line << " in " << s.seconds << " s -> " << survey.sparse().string();
  for (const auto& [camera, fx] : s.self_calibrated) {
    line << "\nsfm: " << camera << ": self-calibrated focal " << fx << " px -> "
         << (survey.sparse() / (camera + ".yaml")).string();
  }
  std::ostringstream summary;
  summary << s.images_registered << " of " << s.images_total << " images registered, " << s.points
          << " points, " << s.mean_reprojection_error_px << " px";
  StageReport report;
  report.lines.push_back(line.str());
  report.warnings = s.warnings;
  report.summary = summary.str();
  return report;
}

}  // namespace auv::recon::sfm
