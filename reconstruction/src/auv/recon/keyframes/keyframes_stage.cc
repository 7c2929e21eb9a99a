#include "auv/recon/keyframes/keyframes_stage.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <sstream>

#include <nlohmann/json.hpp>

#include "auv/recon/common/option_set.h"
#include "auv/recon/common/progress.h"
#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/staged_output.h"
#include "auv/recon/masks/mask.h"

namespace fs = std::filesystem;

namespace auv::recon::keyframes {

namespace {
const char* kStage = "keyframes";

std::string fixed(double value, int decimals) {
  char text[64];
  std::snprintf(text, sizeof(text), "%.*f", decimals, value);
  return text;
}

/// A CSV field, quoted when it holds a comma or a quote.
std::string csvField(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) {
    if (c == '"') quoted += '"';
    quoted += c;
  }
  return quoted + "\"";
}

std::string indexCsv(const std::vector<VideoKeyframes>& videos) {
  std::ostringstream out;
  out << "file,video,frame,camera_time_s,sim_time_s,sharpness,motion_px,tracked\n";
  for (const auto& video : videos) {
    for (const auto& row : video.keyframes) {
      out << csvField(row.file) << ',' << csvField(row.video) << ',' << row.frame << ','
          << fixed(row.camera_time_s, 6) << ','
          << (row.sim_time_s ? fixed(*row.sim_time_s, 6) : std::string()) << ','
          << fixed(row.sharpness, 2) << ',' << fixed(row.motion_px, 1) << ',' << row.tracked
          << '\n';
    }
  }
  return out.str();
}

std::string rejectedCsv(const std::vector<VideoKeyframes>& videos) {
  std::ostringstream out;
  out << "video,frame,reason,sharpness,brightness,detail\n";
  for (const auto& video : videos) {
    for (const auto& r : video.rejected) {
      out << csvField(video.video) << ',' << r.frame << ',' << r.reason << ','
          << fixed(r.sharpness, 2) << ',' << fixed(r.brightness, 1) << ',' << csvField(r.detail)
          << '\n';
    }
  }
  return out.str();
}

nlohmann::json optionsJson(const KeyframesStageOptions& o) {
  const KeyframeOptions& s = o.selection;
  return {{"analysis_width", s.analysis_width},
          {"min_motion", s.min_motion},
          {"min_tracked_fraction", s.min_tracked_fraction},
          {"max_features", s.max_features},
          {"feature_quality", s.feature_quality},
          {"feature_min_distance", s.feature_min_distance},
          {"lk_window", s.lk_window},
          {"lk_levels", s.lk_levels},
          {"max_fb_error", s.max_fb_error},
          {"candidate_frames", s.candidate_frames},
          {"max_candidate_frames", s.max_candidate_frames},
          {"min_brightness", s.min_brightness},
          {"min_sharpness", s.min_sharpness},
          {"min_relative_sharpness", s.min_relative_sharpness},
          {"sharpness_history", s.sharpness_history},
          {"min_features", s.min_features},
          {"png_compression", o.video.png_compression},
          {"keep_damaged", o.video.keep_damaged}};
}

nlohmann::json cameraJson(const CameraKeyframes& camera) {
  nlohmann::json videos = nlohmann::json::array();
  double seconds = 0, recorded_s = 0;
  SelectorCounts total;
  for (const auto& v : camera.videos) {
    const double duration = v.frame_rate > 0 ? v.frames_read / v.frame_rate : 0;
    videos.push_back({{"video", v.video},
                      {"frames", v.frames_read},
                      {"frames_expected", v.frames_expected},
                      {"frame_rate_hz", v.frame_rate},
                      {"keyframes", v.keyframes.size()},
                      {"rejected", v.rejected.size()},
                      {"sidecar", v.has_sidecar},
                      {"seconds", v.seconds},
                      {"problem", v.problem}});
    seconds += v.seconds;
    recorded_s += duration;
    total.candidates += v.counts.candidates;
    total.rejected_dark += v.counts.rejected_dark;
    total.rejected_blurry += v.counts.rejected_blurry;
    total.rejected_featureless += v.counts.rejected_featureless;
    total.triggers_motion += v.counts.triggers_motion;
    total.triggers_tracking += v.counts.triggers_tracking;
    total.reference_resets += v.counts.reference_resets;
    total.windows_dropped += v.counts.windows_dropped;
  }
  return {{"videos", videos},
          {"frames", camera.frames},
          {"keyframes", camera.keyframes},
          {"candidates", total.candidates},
          {"rejected_dark", total.rejected_dark},
          {"rejected_blurry", total.rejected_blurry},
          {"rejected_featureless", total.rejected_featureless},
          {"triggers_motion", total.triggers_motion},
          {"triggers_tracking_lost", total.triggers_tracking},
          {"blur_reference_resets", total.reference_resets},
          {"windows_dropped", total.windows_dropped},
          {"seconds", seconds},
          {"x_real_time", seconds > 0 ? recorded_s / seconds : 0.0}};
}
}  // namespace

void KeyframesStageOptions::check() const {
  selection.check();
  AUV_RECON_CHECK_OPTION(video.png_compression >= 0 && video.png_compression <= 9,
                         video.png_compression, "must be in [0, 9]");
  for (const auto& camera : cameras) {
    AUV_RECON_CHECK_OPTION(
        !camera.empty() && camera.find('/') == std::string::npos && camera[0] != '.', camera,
        "must be a camera folder name");
  }
}

void KeyframesStageOptions::bind(OptionSet& set) {
  KeyframeOptions& s = selection;
  set.add("camera", &cameras, "camera id (folder of recordings/); repeatable; all");
  set.add("min_motion", &s.min_motion,
          "fraction of the image width: median feature motion for a new keyframe");
  set.add("min_tracked_fraction", &s.min_tracked_fraction,
          "new keyframe when fewer of the keyframe's features are still tracked");
  set.add("candidate_frames", &s.candidate_frames, "frames compared by sharpness after a trigger");
  set.add("max_candidate_frames", &s.max_candidate_frames,
          "frames a window may grow to while every candidate is refused");
  set.add("min_brightness", &s.min_brightness, "mean grey level (0-255): darker is refused");
  set.add("min_sharpness", &s.min_sharpness,
          "variance of the Laplacian below which a frame is refused as blurry");
  set.add("min_relative_sharpness", &s.min_relative_sharpness,
          "refused as blurry below this fraction of the last keyframes' median sharpness");
  set.add("sharpness_history", &s.sharpness_history, "keyframes in that median");
  set.add("min_features", &s.min_features, "corners a keyframe needs (else featureless)");
  set.add("analysis_width", &s.analysis_width,
          "px: tracking and sharpness on frames reduced to this width (0 = full size)");
  set.add("max_features", &s.max_features, "Shi-Tomasi corners per keyframe");
  set.add("feature_quality", &s.feature_quality, "corner quality (fraction of the best)");
  set.add("feature_min_distance", &s.feature_min_distance, "fraction of the width between corners");
  set.add("lk_window", &s.lk_window, "px (analysis resolution): Lucas-Kanade window, odd");
  set.add("lk_levels", &s.lk_levels, "Lucas-Kanade pyramid levels");
  set.add("max_fb_error", &s.max_fb_error,
          "px (analysis resolution): forward-backward tracking check (0 = off)");
  set.add("png_compression", &video.png_compression, "PNG compression level 0-9");
  set.add("keep_damaged", &video.keep_damaged,
          "keep the keyframes of a truncated/damaged video up to the damage (else an error)");
}

std::vector<fs::path> listVideos(const fs::path& folder) {
  return listFiles(folder, videoExtensions());
}

KeyframesStageResult runKeyframesStage(const Survey& survey, const KeyframesStageOptions& options) {
  options.check();
  const auto start = std::chrono::steady_clock::now();
  Survey::requireExists(survey.recordings(), kStage, "pull");
  std::vector<std::string> cameras = options.cameras;
  if (cameras.empty()) cameras = Survey::cameraFolders(survey.recordings(), kStage);

  // Check every camera before the long work: a typo fails in a second, not after an hour.
  std::vector<std::vector<fs::path>> videos;
  size_t total_frames = 0;
  for (const auto& camera : cameras) {
    const fs::path folder = survey.recordings() / camera;
    std::error_code error;
    if (!fs::is_directory(folder, error)) {
      throw StageError(kStage, folder.string() + ": no such camera folder");
    }
    videos.push_back(listVideos(folder));
    if (videos.back().empty()) {
      throw StageError(kStage, folder.string() + ": no videos (.mp4 .avi .mov .mkv)");
    }
    for (const auto& video : videos.back()) total_frames += expectedFrameCount(video);
  }

  KeyframesStageResult result;
  std::vector<std::unique_ptr<StagedOutput>> outputs;
  Progress progress("keyframes", "frames", total_frames);
  for (size_t c = 0; c < cameras.size(); ++c) {
    outputs.push_back(std::make_unique<StagedOutput>(survey.keyframes() / cameras[c]));
    CameraKeyframes camera;
    camera.camera = cameras[c];
    // A camera mask (masks/mask.h) keeps the tracked corners off a burned-in overlay.
    VideoOptions video_options = options.video;
    const fs::path mask_file = masks::cameraMaskFile(survey, cameras[c]);
    std::error_code mask_error;
    if (fs::is_regular_file(mask_file, mask_error)) {
      video_options.mask = masks::loadMask(mask_file, cv::Size(), kStage);
      video_options.mask_file = mask_file.string();
    }
    for (const auto& video : videos[c]) {
      VideoKeyframes v = selectVideoKeyframes(video, outputs.back()->path(), options.selection,
                                              video_options, [&] { progress.advance(); });
      camera.frames += v.frames_read;
      camera.keyframes += static_cast<int>(v.keyframes.size());
      camera.rejected += static_cast<int>(v.rejected.size());
      if (!v.problem.empty()) {
        result.problems.push_back(video.string() + ": " + v.problem);
        progress.message("keyframes: " + video.string() + ": " + v.problem +
                         " (keyframes before the damage kept)");
      }
      camera.videos.push_back(std::move(v));
    }
    if (camera.keyframes == 0) {
      throw StageError(kStage, (survey.recordings() / cameras[c]).string() +
                                   ": no usable keyframe (every candidate refused: see the "
                                   "counts; too dark, blurry or featureless)");
    }
    writeFileAtomically(outputs.back()->path() / "index.csv", indexCsv(camera.videos));
    writeFileAtomically(outputs.back()->path() / "rejected.csv", rejectedCsv(camera.videos));
    result.cameras.push_back(std::move(camera));
  }
  progress.finish();
  for (auto& output : outputs) output->commit();
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // The report keeps the cameras of earlier runs that this one did not redo.
  nlohmann::json section = readReportSection(survey.report(), kStage);
  if (!section.contains("cameras") || !section["cameras"].is_object()) {
    section["cameras"] = nlohmann::json::object();
  }
  for (const auto& camera : result.cameras) section["cameras"][camera.camera] = cameraJson(camera);
  section["seconds"] = result.seconds;
  section["options"] = optionsJson(options);
  section["problems"] = result.problems;
  updateReport(survey.report(), kStage, section);
  return result;
}

StageReport KeyframesStage::runWith(const Survey& survey,
                                    const KeyframesStageOptions& options) const {
  const KeyframesStageResult result = runKeyframesStage(survey, options);
  StageReport report;
  int keyframes = 0;
  for (const auto& camera : result.cameras) {
    std::ostringstream line;
    line << "keyframes: " << camera.camera << ": " << camera.keyframes << " keyframes of "
         << camera.frames << " frames (" << camera.videos.size() << " videos), " << camera.rejected
         << " frames refused (rejected.csv)";
    report.lines.push_back(line.str());
    keyframes += camera.keyframes;
  }
  report.warnings = result.problems;
  std::ostringstream done;
  done << "keyframes: done in " << result.seconds << " s -> " << survey.keyframes().string();
  report.lines.push_back(done.str());
  report.summary = std::to_string(keyframes) + " keyframes from " +
                   std::to_string(result.cameras.size()) + " cameras";
  return report;
}

}  // namespace auv::recon::keyframes
