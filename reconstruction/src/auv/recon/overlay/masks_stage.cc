#include "auv/recon/overlay/masks_stage.h"

#include <algorithm>
#include <chrono>
#include <sstream>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "auv/recon/common/option_set.h"
#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/staged_output.h"
#include "auv/recon/keyframes/keyframes_stage.h"
#include "auv/recon/masks/mask.h"

namespace fs = std::filesystem;

namespace auv::recon::overlay {
namespace {

constexpr const char* kStage = "masks";

bool isFile(const fs::path& file) {
  std::error_code error;
  return fs::is_regular_file(file, error);
}

// Writes masks/<camera>.png from the static overlay of the camera's videos.
void detectCamera(const Survey& survey, const MasksStageOptions& options,
                  CameraMaskReport& report) {
  const fs::path target = masks::cameraMaskFile(survey, report.camera);
  if (isFile(target) && !options.replace) {
    throw StageError(kStage, target.string() +
                                 " exists: a mask is never overwritten (it may be the user's); "
                                 "pass --replace to write the detected one over it");
  }
  const std::vector<fs::path> videos = keyframes::listVideos(survey.recordings() / report.camera);
  if (videos.empty()) {
    throw StageError(kStage, "camera '" + report.camera + "': no video in " +
                                 (survey.recordings() / report.camera).string() +
                                 " (the detector needs the moving scene of a video)");
  }
  for (const fs::path& video : videos) report.videos.push_back(video.filename().string());
  try {
    report.detection = detectInVideos(videos, options.overlay);
  } catch (const std::runtime_error& e) {
    throw StageError(kStage, "camera '" + report.camera + "': " + e.what());
  }
  std::vector<uint8_t> png;
  cv::imencode(".png", report.detection.mask, png);
  fs::create_directories(target.parent_path());
  writeFileAtomically(target, std::string(png.begin(), png.end()));
  report.detected = true;
}

// Loads and size-checks the mask of every keyframe of the camera (StageError naming a bad one).
void checkCamera(const Survey& survey, CameraMaskReport& report) {
  report.camera_mask = isFile(masks::cameraMaskFile(survey, report.camera));
  std::error_code error;
  const fs::path own = masks::masksFolder(survey) / report.camera;
  if (fs::is_directory(own, error)) report.image_masks = listFiles(own, {".png"}).size();
  const fs::path keyframes = survey.keyframes() / report.camera;
  if (!fs::is_directory(keyframes, error)) return;
  for (const fs::path& image : listFiles(keyframes, {".png", ".jpg", ".jpeg", ".tif", ".tiff"})) {
    const auto file = masks::findMask(survey, report.camera, image.filename().string());
    if (!file) continue;
    const cv::Mat full = cv::imread(image.string(), cv::IMREAD_GRAYSCALE);
    if (full.empty()) throw StageError(kStage, image.string() + ": not a readable image");
    masks::loadMask(*file, full.size(), kStage, "keyframe " + image.string());
    ++report.images_checked;
  }
}

}  // namespace

void MasksStageOptions::check() const { overlay.check(); }

void MasksStageOptions::bind(OptionSet& set) {
  set.add("detect_overlay", &detect_overlay,
          "detect burned-in overlays in each camera's videos and write masks/<camera>.png");
  set.add("replace", &replace, "overwrite an existing masks/<camera>.png with the detected one");
  set.add("camera", &cameras, "only this camera (repeatable; default all)");
  set.add("samples", &overlay.samples, "frames sampled evenly over the camera's videos");
  set.add("max_std", &overlay.max_std,
          "grey levels: temporal standard deviation below which a pixel is static");
  set.add("min_gradient", &overlay.min_gradient,
          "grey levels/px: mean-image gradient above which a static pixel is an overlay edge");
  set.add("max_std_flat", &overlay.max_std_flat,
          "grey levels: temporal standard deviation below which a pixel is overlay whatever its "
          "contrast (0 = edges only)");
  set.add("close_px", &overlay.close_px, "px: closing that joins text strokes into blocks");
  set.add("min_area_px", &overlay.min_area_px, "px: smaller overlay blobs are dropped");
  set.add("dilate_px", &overlay.dilate_px, "px: margin added around the overlay");
  set.add("min_moving_fraction", &overlay.min_moving_fraction,
          "fraction of pixels that must vary (> 2 x max_std) for a detection");
}

MasksStageResult runMasksStage(const Survey& survey, const MasksStageOptions& options) {
  options.check();
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::string> cameras = options.cameras;
  if (cameras.empty()) {
    if (options.detect_overlay) {
      Survey::requireExists(survey.recordings(), kStage, "pull` or `auv recon import --video");
      cameras = Survey::cameraFolders(survey.recordings(), kStage);
    } else {
      Survey::requireExists(survey.keyframes(), kStage, "keyframes` or `auv recon import");
      cameras = Survey::cameraFolders(survey.keyframes(), kStage);
    }
  }
  MasksStageResult result;
  for (const std::string& camera : cameras) {
    CameraMaskReport report;
    report.camera = camera;
    if (options.detect_overlay) detectCamera(survey, options, report);
    checkCamera(survey, report);
    result.cameras.push_back(std::move(report));
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  nlohmann::json cameras_json = nlohmann::json::object();
  for (const CameraMaskReport& c : result.cameras) {
    nlohmann::json entry = {{"camera_mask", c.camera_mask},
                            {"image_masks", c.image_masks},
                            {"keyframes_checked", c.images_checked},
                            {"detected", c.detected}};
    if (c.detected) {
      entry["detection"] = {{"videos", c.videos},
                            {"frames", c.detection.frames},
                            {"moving_fraction", c.detection.moving_fraction},
                            {"masked_fraction", c.detection.masked_fraction},
                            {"regions", c.detection.regions}};
    }
    cameras_json[c.camera] = entry;
  }
  const OverlayOptions& o = options.overlay;
  updateReport(survey.report(), kStage,
               {{"cameras", cameras_json},
                {"seconds", result.seconds},
                {"options",
                 {{"detect_overlay", options.detect_overlay},
                  {"replace", options.replace},
                  {"samples", o.samples},
                  {"max_std", o.max_std},
                  {"min_gradient", o.min_gradient},
                  {"max_std_flat", o.max_std_flat},
                  {"close_px", o.close_px},
                  {"min_area_px", o.min_area_px},
                  {"dilate_px", o.dilate_px},
                  {"min_moving_fraction", o.min_moving_fraction}}}});
  return result;
}

StageReport MasksStage::runWith(const Survey& survey, const MasksStageOptions& options) const {
  const MasksStageResult result = runMasksStage(survey, options);
  StageReport report;
  size_t detected = 0;
  for (const CameraMaskReport& c : result.cameras) {
    std::ostringstream line;
    line << "masks: " << c.camera << ": ";
    if (c.detected) {
      ++detected;
      line << "detected " << c.detection.regions << " overlay region(s), "
           << 100 * c.detection.masked_fraction << " % of the image, over " << c.detection.frames
           << " frames -> " << masks::cameraMaskFile(survey, c.camera).string() << "; ";
    }
    line << (c.camera_mask ? "camera mask" : "no camera mask") << ", " << c.image_masks
         << " image mask(s), " << c.images_checked << " keyframe(s) checked";
    report.lines.push_back(line.str());
  }
  report.summary = std::to_string(result.cameras.size()) + " camera(s), " +
                   std::to_string(detected) + " overlay mask(s) detected";
  return report;
}

}  // namespace auv::recon::overlay
