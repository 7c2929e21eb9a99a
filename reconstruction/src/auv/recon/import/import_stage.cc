#include "auv/recon/import/import_stage.h"

#include <chrono>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "auv/recon/common/option_set.h"
#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/import/photos.h"
#include "auv/recon/import/video.h"

namespace fs = std::filesystem;

namespace auv::recon::import {
namespace {

constexpr const char* kStage = "import";

nlohmann::json cameraJson(const ImportedCamera& c, const ImportStageOptions& options) {
  const IntrinsicsPrior& p = c.prior;
  nlohmann::json camera = {{"kind", c.kind},
                           {"source", c.kind == "video" ? options.video : options.images},
                           {"group", c.group},
                           {"prior",
                            {{"file", c.written.back().string()},
                             {"focal_px", p.focal_px},
                             {"source", p.source},
                             {"field_of_view_deg", fieldOfViewDeg(p.focal_px, p.image_size)},
                             {"width", p.image_size.width},
                             {"height", p.image_size.height},
                             {"exif_ignored", p.ignored}}}};
  if (c.kind == "video") {
    camera["frames"] = c.frames;
  } else {
    camera["images"] = c.images;
    camera["turned_upright"] = c.upright_turned;
    camera["with_capture_time"] = c.with_time;
  }
  return camera;
}

}  // namespace

std::string cameraIdFrom(const std::string& name) {
  std::string id = name.empty() ? "camera" : name;
  for (char& c : id) {
    if (c == ',' || c == '/') c = '_';
  }
  if (id[0] == '.') id[0] = '_';
  return id;
}

void ImportStageOptions::check() const {
  if (images.empty() == video.empty()) {
    throw std::invalid_argument("give one of --images <folder> and --video <file>");
  }
  if (!camera.empty() && (camera.find('/') != std::string::npos || camera[0] == '.' ||
                          camera.find(',') != std::string::npos)) {
    throw std::invalid_argument("--camera " + camera +
                                ": must be a camera name (no '/' or ',', not starting with '.')");
  }
  AUV_RECON_CHECK_OPTION(png_compression >= 0 && png_compression <= 9, png_compression,
                         "must be in 0-9");
  prior.check();
}

void ImportStageOptions::bind(OptionSet& set) {
  set.add("images", &images, "folder of photos (.jpg .jpeg .png .tif .tiff .bmp .webp)");
  set.add("video", &video, "one video file (.mp4 .avi .mov .mkv)");
  set.add("camera", &camera,
          "camera id (default: the folder's name or the video's stem); a folder of several "
          "cameras or sizes gives <camera>, <camera>-2, ...");
  set.add("replace", &replace, "replace keyframes/<camera> or a video of the same name");
  set.add("focal_px", &prior.focal_px,
          "px: the focal length of the upright images, if known (0: from EXIF or the default)");
  set.add("focal_35mm", &prior.focal_35mm,
          "mm: the 35 mm equivalent focal length, if known (0: from EXIF or the default)");
  set.add("default_focal_factor", &prior.default_focal_factor,
          "x the larger image side: the focal when nothing else is known");
  set.add("min_fov_deg", &prior.min_fov_deg, "deg: EXIF focals giving a narrower view are lies");
  set.add("max_fov_deg", &prior.max_fov_deg, "deg: EXIF focals giving a wider view are lies");
  set.add("png_compression", &png_compression, "PNG compression level 0-9 of imported photos");
}

ImportStageResult runImportStage(const Survey& survey, const ImportStageOptions& options) {
  options.check();
  const auto start = std::chrono::steady_clock::now();
  ImportStageResult result;
  if (!options.images.empty()) {
    importPhotos(survey, options, result);
  } else {
    importVideo(survey, options, result);
  }
  for (const SkippedFile& skipped : result.skipped) {
    result.warnings.push_back(skipped.file + ": skipped: " + skipped.reason);
  }
  for (const ImportedCamera& camera : result.cameras) {
    for (const std::string& ignored : camera.prior.ignored) {
      result.warnings.push_back("camera '" + camera.camera + "': EXIF " + ignored +
                                ": not used for the intrinsics prior (" + camera.prior.source +
                                " used)");
    }
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // The report keeps the cameras imported earlier.
  nlohmann::json section = readReportSection(survey.report(), kStage);
  if (!section.contains("cameras") || !section["cameras"].is_object()) {
    section["cameras"] = nlohmann::json::object();
  }
  for (const ImportedCamera& camera : result.cameras) {
    section["cameras"][camera.camera] = cameraJson(camera, options);
  }
  nlohmann::json skipped = nlohmann::json::array();
  for (const SkippedFile& s : result.skipped)
    skipped.push_back({{"file", s.file}, {"reason", s.reason}});
  section["last_run"] = {
      {"skipped", skipped}, {"warnings", result.warnings}, {"seconds", result.seconds}};
  updateReport(survey.report(), kStage, section);
  return result;
}

StageReport ImportStage::runWith(const Survey& survey, const ImportStageOptions& options) const {
  const ImportStageResult result = runImportStage(survey, options);
  StageReport report;
  int imported = 0;
  for (const ImportedCamera& c : result.cameras) {
    std::ostringstream line;
    line << "import: " << c.camera << ": ";
    if (c.kind == "video") {
      line << c.frames << " frames";
    } else {
      line << c.images << " photos";
      imported += c.images;
      if (c.upright_turned > 0) line << " (" << c.upright_turned << " turned upright)";
    }
    line << " [" << c.group << "], focal prior " << c.prior.focal_px << " px (" << c.prior.source
         << ") -> " << c.written.front().string();
    report.lines.push_back(line.str());
  }
  const bool photos = !options.images.empty();
  report.lines.push_back(std::string("import: next: auv recon run ") + survey.root().string() +
                         (photos ? " --from correct" : ""));
  report.warnings = result.warnings;
  std::ostringstream summary;
  if (photos) {
    summary << imported << " photos in " << result.cameras.size() << " camera(s), "
            << result.skipped.size() << " skipped";
  } else {
    summary << result.cameras.front().frames << " video frames";
  }
  report.summary = summary.str();
  return report;
}

}  // namespace auv::recon::import
