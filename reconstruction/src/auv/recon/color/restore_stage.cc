#include "auv/recon/color/restore_stage.h"

#include <chrono>
#include <map>
#include <memory>
#include <sstream>

#include <open3d/geometry/TriangleMesh.h>
#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "auv/recon/calibration/calibration.h"
#include "auv/recon/common/option_set.h"
#include "auv/recon/common/progress.h"
#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/staged_output.h"
#include "auv/recon/scene/colmap_text.h"
#include "auv/recon/scene/mesh_io.h"
#include "auv/recon/texture/rasterizer.h"

namespace fs = std::filesystem;

namespace auv::recon::color {

namespace {
const char* kStage = "restore";

nlohmann::json tripleJson(const Eigen::Array3d& v) { return {v[0], v[1], v[2]}; }

// One keyframe: where it is, its pinhole view, and the map from the filmed (distorted) image.
struct Keyframe {
  std::string name;
  fs::path file;
  texture::ViewGeometry view;
  const cv::Mat* map1 = nullptr;
  const cv::Mat* map2 = nullptr;
};

// The filmed keyframe undistorted to its sparse/ pinhole camera (what corrected/ holds, before
// any colour change).
cv::Mat loadKeyframe(const Keyframe& k) {
  cv::Mat image = cv::imread(k.file.string(), cv::IMREAD_COLOR);
  if (image.empty()) throw StageError(kStage, k.file.string() + ": not a readable image");
  if (image.cols != k.view.width() || image.rows != k.view.height()) {
    throw StageError(kStage, k.file.string() + ": " + std::to_string(image.cols) + "x" +
                                 std::to_string(image.rows) + " px, but its camera " +
                                 std::to_string(k.view.camera.id) + " in sparse/cameras.txt is " +
                                 std::to_string(k.view.width()) + "x" +
                                 std::to_string(k.view.height()));
  }
  if (k.map1) {
    cv::Mat undistorted;
    cv::remap(image, undistorted, *k.map1, *k.map2, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    image = undistorted;
  }
  return image;
}

// Range (distance along the ray) of every pixel from the mesh's z-buffer; +inf where none.
cv::Mat1f rangeMap(const open3d::geometry::TriangleMesh& mesh, const texture::ViewGeometry& view,
                   const cv::Mat1f& ray_length) {
  const texture::RasterBuffers raster = texture::rasterize(mesh.vertices_, mesh.triangles_, view);
  cv::Mat1f range = raster.depth.mul(ray_length);
  return range;
}

cv::Mat1f rayLengthMap(const texture::ViewGeometry& view) {
  const scene::Camera& c = view.camera;
  const cv::Mat cos4 = cos4Map(cv::Size(c.width, c.height), c.fx, c.fy, c.cx, c.cy);
  cv::Mat1f length;
  cv::pow(cos4, -0.25, length);  // 1 / cos of the off-axis angle
  return length;
}

// E(X) of every pixel's surface point (BGR); 1 where there is none; empty for uniform light.
cv::Mat illuminantMap(const WaterModel& water, const texture::ViewGeometry& view,
                      const cv::Mat1f& range) {
  if (water.illuminant_gradient.isZero()) return cv::Mat();
  const scene::Camera& c = view.camera;
  const Eigen::Isometry3d camera_to_world = view.world_to_camera.inverse();
  cv::Mat3f out(range.size(), cv::Vec3f(1, 1, 1));
  for (int y = 0; y < range.rows; ++y) {
    for (int x = 0; x < range.cols; ++x) {
      const float r = range(y, x);
      if (!std::isfinite(r) || r <= 0) continue;
      const Eigen::Vector3d ray((x - c.cx) / c.fx, (y - c.cy) / c.fy, 1.0);
      const Eigen::Array3d e = water.illuminant(camera_to_world * (ray.normalized() * r));
      out(y, x) =
          cv::Vec3f(static_cast<float>(e[2]), static_cast<float>(e[1]), static_cast<float>(e[0]));
    }
  }
  return out;
}

// The keyframes of the pinhole model (Survey::pinholeWorkspace), with undistortion maps per
// camera folder (in `maps`) onto its pinhole camera: the lens that sfm self-calibrated (a
// camera of `lenses`, sparse/, with distortion), else the calibration's.
std::vector<Keyframe> listKeyframes(const Survey& survey, const scene::Reconstruction& model,
                                    const scene::Reconstruction& lenses,
                                    std::map<std::string, std::pair<cv::Mat, cv::Mat>>& maps) {
  std::vector<Keyframe> keyframes;
  for (const auto& [id, image] : model.images) {
    const scene::Camera& camera = model.cameraOf(image);
    const auto self_calibrated = lenses.cameras.find(camera.id);
    if (camera.hasDistortion()) {
      throw StageError(kStage, "camera " + std::to_string(camera.id) + " of " +
                                   (survey.sparse() / "cameras.txt").string() +
                                   " has lens distortion: the restoration needs the undistorted "
                                   "pinhole cameras of the corrected images");
    }
    Keyframe k;
    k.name = image.name;
    k.file = survey.keyframes() / image.name;
    if (!fs::exists(k.file)) {
      throw StageError(kStage, k.file.string() + ": keyframe of " + image.name +
                                   " not found (run `auv recon keyframes` first)");
    }
    k.view.camera = camera;
    k.view.world_to_camera = image.worldToCamera();
    const std::string folder = fs::path(image.name).parent_path().string();
    if (!maps.count(folder)) {
      const fs::path calibration_file = survey.calibrationFile(folder);
      calibration::CameraCalibration lens;
      if (self_calibrated != lenses.cameras.end() && self_calibrated->second.hasDistortion()) {
        lens = calibration::calibrationOf(self_calibrated->second);
      } else if (fs::exists(calibration_file)) {
        lens = calibration::readCalibration(calibration_file, kStage);
      }
      if (!lens.distortion.empty() && cv::countNonZero(lens.distortion != 0) > 0) {
        cv::Mat map1, map2;
        cv::initUndistortRectifyMap(lens.camera_matrix, lens.distortion, cv::Mat(),
                                    calibration::calibrationOf(camera).camera_matrix,
                                    cv::Size(camera.width, camera.height), CV_16SC2, map1, map2);
        maps[folder] = {map1, map2};
      }
    }
    keyframes.push_back(std::move(k));
  }
  for (Keyframe& k : keyframes) {
    const auto it = maps.find(fs::path(k.name).parent_path().string());
    if (it != maps.end()) {
      k.map1 = &it->second.first;
      k.map2 = &it->second.second;
    }
  }

  return keyframes;
}

nlohmann::json reportSection(const RestoreStageResult& r, const RestoreStageOptions& options) {
  const WaterFitOptions& o = options.water;
  return {{"images", r.images},
          {"output", "restored/"},
          {"water",
           {{"backscatter_infinity", tripleJson(r.model.backscatter_infinity)},
            {"backscatter_coefficient", tripleJson(r.model.backscatter_coefficient)},
            {"residual_signal", tripleJson(r.model.residual_signal)},
            {"residual_decay", tripleJson(r.model.residual_decay)},
            {"attenuation", tripleJson(r.model.attenuation)},
            {"vignetting", r.model.vignetting},
            {"white_balance", tripleJson(r.model.white_balance)},
            {"illuminant_gradient",
             {tripleJson(r.model.illuminant_gradient.row(0).transpose().array()),
              tripleJson(r.model.illuminant_gradient.row(1).transpose().array()),
              tripleJson(r.model.illuminant_gradient.row(2).transpose().array())}},
            {"illuminant_origin", tripleJson(r.model.illuminant_origin.array())}}},
          {"backscatter_fit",
           {{"samples", r.backscatter.samples},
            {"dark_samples", r.backscatter.dark_samples},
            {"rms", tripleJson(r.backscatter.rms)}}},
          {"attenuation_fit",
           {{"observations", r.attenuation.observations},
            {"points", r.attenuation.points},
            {"rms_log", tripleJson(r.attenuation.rms)}}},
          {"seconds", r.seconds},
          {"options",
           {{"range_bins", o.range_bins},
            {"dark_fraction", o.dark_fraction},
            {"min_signal", o.min_signal},
            {"min_views", o.min_views},
            {"min_range_ratio", o.min_range_ratio},
            {"max_attenuation", o.max_attenuation},
            {"estimate_vignetting", o.estimate_vignetting},
            {"loss_scale", o.loss_scale},
            {"refine_jointly", o.refine_jointly},
            {"joint_loss_scale", o.joint_loss_scale},
            {"white_balance", o.white_balance},
            {"max_gain", o.max_gain},
            {"illuminant", o.illuminant},
            {"samples_per_image", options.samples_per_image},
            {"max_points", options.max_points},
            {"depth_tolerance", options.depth_tolerance},
            {"blur_px", options.blur_px}}}};
}

}  // namespace

fs::path restoredFolder(const Survey& survey) { return survey.root() / "restored"; }

void RestoreStageOptions::check() const {
  water.check();
  AUV_RECON_CHECK_OPTION(samples_per_image >= 100, samples_per_image, "must be >= 100");
  AUV_RECON_CHECK_OPTION(max_points >= 10, max_points, "must be >= 10");
  AUV_RECON_CHECK_OPTION(depth_tolerance > 0 && depth_tolerance < 1, depth_tolerance,
                         "must be in (0, 1)");
  AUV_RECON_CHECK_OPTION(blur_px >= 1 && blur_px % 2 == 1 && blur_px <= 31, blur_px,
                         "must be odd, in [1, 31]");
  AUV_RECON_CHECK_OPTION(png_compression >= 0 && png_compression <= 9, png_compression,
                         "must be in [0, 9]");
}

void RestoreStageOptions::bind(OptionSet& set) {
  set.add("range_bins", &water.range_bins, "range bins of the backscatter's dark pixels");
  set.add("dark_fraction", &water.dark_fraction, "darkest fraction of each range bin");
  set.add("min_signal", &water.min_signal,
          "linear direct signal below which an observation is not used (attenuation fit)");
  set.add("min_views", &water.min_views, "views a surface point needs (attenuation fit)");
  set.add("min_range_ratio", &water.min_range_ratio,
          "farthest / nearest range of a point's views at least (attenuation fit)");
  set.add("max_attenuation", &water.max_attenuation, "1/unit: bound of the coefficients");
  set.add("estimate_vignetting", &water.estimate_vignetting,
          "fit the lens vignetting with the attenuation");
  set.add("loss_scale", &water.loss_scale, "Cauchy scale of the attenuation residuals (log)");
  set.add("refine_jointly", &water.refine_jointly,
          "refine attenuation and backscatter together on all observations (linear light)");
  set.add("joint_loss_scale", &water.joint_loss_scale, "Huber scale of the joint refinement");
  set.add("white_balance", &water.white_balance, "grey_world or none, after the restoration");
  set.add("max_gain", &water.max_gain, "largest gain the restoration applies to a pixel");
  set.add("illuminant", &water.illuminant,
          "uniform, or gradient: the light log-linear in position (fades with depth)");
  set.add("samples_per_image", &samples_per_image, "pixels per keyframe (backscatter fit)");
  set.add("max_points", &max_points, "mesh vertices followed across the views");
  set.add("depth_tolerance", &depth_tolerance, "relative z-buffer tolerance (visibility)");
  set.add("blur_px", &blur_px, "box filter of the sampled colours (odd px, 1 = none)");
  set.add("png_compression", &png_compression, "PNG compression level 0-9");
}

RestoreStageResult runRestoreStage(const Survey& survey, const RestoreStageOptions& options) {
  options.check();
  const auto start = std::chrono::steady_clock::now();
  const fs::path mesh_file = survey.mesh() / "mesh.ply";
  const fs::path model_folder = survey.pinholeWorkspace().model;
  Survey::requireExists(model_folder / "images.txt", kStage, "sfm");
  const open3d::geometry::TriangleMesh mesh = scene::readMesh(mesh_file, kStage);
  scene::Reconstruction model, lenses;
  try {
    model = scene::readColmapText(model_folder);
    lenses = model_folder == survey.sparse() ? model : scene::readColmapText(survey.sparse());
  } catch (const std::exception& e) {
    throw StageError(kStage, e.what());
  }
  if (model.images.empty()) {
    throw StageError(kStage, (model_folder / "images.txt").string() + ": no registered images");
  }

  std::map<std::string, std::pair<cv::Mat, cv::Mat>> maps;  // undistortion per camera folder
  const std::vector<Keyframe> keyframes = listKeyframes(survey, model, lenses, maps);

  // Pass 1: samples of every keyframe for the fits.
  const size_t vertex_step =
      std::max<size_t>(1, mesh.vertices_.size() / static_cast<size_t>(options.max_points));
  std::vector<RangeSample> samples;
  std::vector<PointObservation> observations;
  Progress progress(kStage, "images", 2 * keyframes.size());
  for (const Keyframe& k : keyframes) {
    const cv::Mat linear = linearFromSrgb(loadKeyframe(k));
    cv::Mat smooth;
    cv::blur(linear, smooth, cv::Size(options.blur_px, options.blur_px));
    const cv::Mat1f length = rayLengthMap(k.view);
    const texture::RasterBuffers raster =
        texture::rasterize(mesh.vertices_, mesh.triangles_, k.view);
    const int step = std::max(1, static_cast<int>(std::sqrt(static_cast<double>(linear.total()) /
                                                            options.samples_per_image)));
    for (int y = step / 2; y < linear.rows; y += step) {
      for (int x = step / 2; x < linear.cols; x += step) {
        const float z = raster.depth(y, x);
        if (!std::isfinite(z)) continue;
        const cv::Vec3f bgr = smooth.at<cv::Vec3f>(y, x);
        samples.push_back({z * length(y, x), Eigen::Array3f(bgr[2], bgr[1], bgr[0]),
                           std::pow(length(y, x), -4.0f)});
      }
    }
    const int margin = options.blur_px / 2 + 2;
    for (size_t v = 0; v < mesh.vertices_.size(); v += vertex_step) {
      const Eigen::Vector3d p = k.view.toCamera(mesh.vertices_[v]);
      if (p.z() <= 0) continue;
      const Eigen::Vector2d uv = k.view.project(p);
      const int x = static_cast<int>(std::lround(uv.x())),
                y = static_cast<int>(std::lround(uv.y()));
      if (x < margin || y < margin || x >= linear.cols - margin || y >= linear.rows - margin) {
        continue;
      }
      if (std::abs(raster.depth(y, x) - p.z()) > options.depth_tolerance * p.z()) continue;
      const cv::Vec3f bgr = smooth.at<cv::Vec3f>(y, x);
      const float k4 = std::pow(length(y, x), -4.0f);
      observations.push_back({static_cast<int32_t>(v / vertex_step), static_cast<float>(p.norm()),
                              k4, Eigen::Array3f(bgr[2], bgr[1], bgr[0])});
    }
    progress.advance();
  }

  RestoreStageResult result;
  WaterModel& water = result.model;
  auto notRestored = [&](const std::string& why) {
    result.not_restored = why;
    fs::remove_all(restoredFolder(survey));
    result.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    updateReport(survey.report(), kStage,
                 {{"images", 0}, {"not_restored", why}, {"seconds", result.seconds}});
    return result;
  };
  try {
    result.backscatter = fitBackscatter(samples, options.water, water);
    result.attenuation = fitAttenuation(observations, options.water, water);
  } catch (const std::invalid_argument& e) {
    return notRestored(mesh_file.string() + " and " + std::to_string(keyframes.size()) +
                       " keyframes: " + e.what());
  }
  // The light's trend across the scene (daylight fading with depth below the surface), relative
  // to where the cameras are.
  std::vector<Eigen::Vector3d> positions;
  for (size_t v = 0; v < mesh.vertices_.size(); v += vertex_step)
    positions.push_back(mesh.vertices_[v]);
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  for (const Keyframe& k : keyframes) origin += k.view.center();
  origin /= static_cast<double>(keyframes.size());
  if (options.water.illuminant == "gradient") {
    try {
      fitIlluminantGradient(result.attenuation.colors, positions, origin, options.water, water);
    } catch (const std::invalid_argument& e) {
      return notRestored(mesh_file.string() + ": " + e.what());
    }
  }
  // Grey world over the restored surface points: the average light left on the scene is not
  // separable from the albedo without a reference.
  if (options.water.white_balance == "grey_world") {
    Eigen::Array3d sum = Eigen::Array3d::Zero(), unlit = Eigen::Array3d::Zero();
    for (const PointObservation& o : observations) {
      const Eigen::Array3d j =
          restoreLinear(o.rgb.cast<double>(), o.range, o.cos4, water, options.water.max_gain);
      unlit += j;
      sum += j / water.illuminant(positions[o.point]);
    }
    // Gains that make the mean grey at the luminance (Rec. 709 weights) the surface had before
    // the light correction: the camera's exposure is kept. The light gradient only
    // redistributes light across the scene; taken at the cameras' mean position, an
    // extrapolated gradient would also set the exposure (a canyon survey came out 2.7x dark).
    if ((sum > 0).all()) water.white_balance = luminance(unlit) / sum;
  }

  // Pass 2: the restored keyframes.
  StagedOutput staged(restoredFolder(survey));
  const std::vector<int> png{cv::IMWRITE_PNG_COMPRESSION, options.png_compression};
  for (const Keyframe& k : keyframes) {
    const cv::Mat image = loadKeyframe(k);
    const cv::Mat1f length = rayLengthMap(k.view);
    const cv::Mat1f range = rangeMap(mesh, k.view, length);
    const scene::Camera& c = k.view.camera;
    const cv::Mat cos4 = cos4Map(image.size(), c.fx, c.fy, c.cx, c.cy);
    const cv::Mat restored =
        restoreImage(image, range, cos4, water, options.water, illuminantMap(water, k.view, range));
    const fs::path out = staged.path() / k.name;
    fs::create_directories(out.parent_path());
    if (!cv::imwrite(out.string(), restored, png)) {
      throw StageError(kStage, out.string() + ": cannot write");
    }
    ++result.images;
    progress.advance();
  }
  progress.finish();
  writeWaterModel(staged.path() / "water.yaml", water,
                  "auv recon restore: water estimated blind from " +
                      std::to_string(keyframes.size()) + " keyframes and their ranges (" +
                      mesh_file.filename().string() + ")");
  staged.commit();

  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const nlohmann::json section = reportSection(result, options);
  updateReport(survey.report(), kStage, section);
  return result;
}

StageReport RestoreStage::runWith(const Survey& survey, const RestoreStageOptions& options) const {
  const RestoreStageResult r = runRestoreStage(survey, options);
  if (!r.not_restored.empty()) {
    StageReport report;
    report.warnings.push_back("colour not restored: " + r.not_restored +
                              "; texture uses the corrected/ images");
    report.summary = "not restored (water not estimable)";
    return report;
  }
  const auto rgb = [](const Eigen::Array3d& v) {
    std::ostringstream s;
    s << "(" << v[0] << ", " << v[1] << ", " << v[2] << ")";
    return s.str();
  };
  StageReport report;
  report.lines.push_back(
      "restore: backscatter at infinity (r, g, b) = " + rgb(r.model.backscatter_infinity) +
      ", coefficient " + rgb(r.model.backscatter_coefficient) + " from " +
      std::to_string(r.backscatter.dark_samples) + " dark pixels");
  report.lines.push_back("restore: attenuation " + rgb(r.model.attenuation) + ", vignetting " +
                         std::to_string(r.model.vignetting) + " from " +
                         std::to_string(r.attenuation.points) + " surface points (" +
                         std::to_string(r.attenuation.observations) + " observations)");
  std::ostringstream done;
  done << "restore: done in " << r.seconds << " s -> " << restoredFolder(survey).string();
  report.lines.push_back(done.str());
  report.summary = std::to_string(r.images) + " images restored";
  return report;
}

}  // namespace auv::recon::color
