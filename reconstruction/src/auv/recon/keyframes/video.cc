#include "auv/recon/keyframes/video.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "auv/recon/common/stage_error.h"

namespace fs = std::filesystem;

namespace auv::recon::keyframes {

namespace {
const char* kStage = "keyframes";

std::string trim(const std::string& text) {
  const size_t begin = text.find_first_not_of(" \t\r\n");
  if (begin == std::string::npos) return "";
  const size_t end = text.find_last_not_of(" \t\r\n");
  return text.substr(begin, end - begin + 1);
}

bool parseDouble(const std::string& text, double& value) {
  char* end = nullptr;
  value = std::strtod(text.c_str(), &end);
  return !text.empty() && end == text.c_str() + text.size() && std::isfinite(value);
}

std::string keyframeName(const fs::path& video, int frame) {
  char digits[16];
  std::snprintf(digits, sizeof(digits), "%06d", frame);
  return video.stem().string() + "_" + digits + ".png";
}
}  // namespace

const std::vector<std::string>& videoExtensions() {
  static const std::vector<std::string> extensions = {".mp4", ".avi", ".mov", ".mkv"};
  return extensions;
}

fs::path sidecarOf(const fs::path& video) { return video.string() + ".frames.csv"; }

std::vector<FrameTime> readFrameTimes(const fs::path& sidecar) {
  std::ifstream in(sidecar);
  if (!in) throw StageError(kStage, sidecar.string() + ": cannot read");
  std::string line;
  if (!std::getline(in, line) || trim(line) != "frame,camera_time_s,sim_time_s") {
    throw StageError(kStage,
                     sidecar.string() + ":1: expected the header 'frame,camera_time_s,sim_time_s'");
  }
  std::vector<FrameTime> times;
  int number = 1;
  while (std::getline(in, line)) {
    ++number;
    line = trim(line);
    if (line.empty()) continue;
    const std::string where = sidecar.string() + ":" + std::to_string(number) + ": ";
    std::vector<std::string> fields;
    std::stringstream row(line);
    std::string field;
    while (std::getline(row, field, ',')) fields.push_back(trim(field));
    if (line.back() == ',') fields.emplace_back();
    if (fields.size() != 3) {
      throw StageError(kStage, where + "expected 3 fields (frame,camera_time_s,sim_time_s), got " +
                                   std::to_string(fields.size()));
    }
    double frame = 0;
    FrameTime time;
    if (!parseDouble(fields[0], frame) || frame != std::floor(frame)) {
      throw StageError(kStage, where + "frame '" + fields[0] + "' is not an integer");
    }
    if (frame != static_cast<double>(times.size())) {  // a negative or huge frame: no cast
      throw StageError(kStage, where + "frame " + fields[0] + " out of order (expected " +
                                   std::to_string(times.size()) + ")");
    }
    if (!parseDouble(fields[1], time.camera_time_s)) {
      throw StageError(kStage, where + "camera_time_s '" + fields[1] + "' is not a number");
    }
    if (!fields[2].empty()) {
      double sim = 0;
      if (!parseDouble(fields[2], sim)) {
        throw StageError(kStage, where + "sim_time_s '" + fields[2] + "' is not a number");
      }
      time.sim_time_s = sim;
    }
    times.push_back(time);
  }
  return times;
}

int expectedFrameCount(const fs::path& video) {
  std::error_code error;
  if (fs::exists(sidecarOf(video), error)) {
    try {
      return static_cast<int>(readFrameTimes(sidecarOf(video)).size());
    } catch (const StageError&) {
      return 0;  // reported when the video itself is processed
    }
  }
  cv::VideoCapture capture(video.string(), cv::CAP_FFMPEG);
  if (!capture.isOpened()) return 0;
  const double count = capture.get(cv::CAP_PROP_FRAME_COUNT);
  return count > 0 ? static_cast<int>(count) : 0;
}

VideoKeyframes selectVideoKeyframes(const fs::path& video, const fs::path& out_folder,
                                    const KeyframeOptions& options,
                                    const VideoOptions& video_options,
                                    const std::function<void()>& on_frame) {
  const auto start = std::chrono::steady_clock::now();
  VideoKeyframes result;
  result.video = video.filename().string();
  std::vector<FrameTime> times;
  std::error_code error;
  result.has_sidecar = fs::exists(sidecarOf(video), error);
  if (result.has_sidecar) times = readFrameTimes(sidecarOf(video));

  cv::VideoCapture capture;
  try {
    capture.open(video.string(), cv::CAP_FFMPEG);
  } catch (const cv::Exception& e) {
    throw StageError(kStage, video.string() + ": cannot open the video: " + e.err);
  }
  if (!capture.isOpened()) {
    throw StageError(
        kStage, video.string() + ": cannot open the video (damaged, truncated or not a video)");
  }
  result.frame_rate = capture.get(cv::CAP_PROP_FPS);
  const double container_count = capture.get(cv::CAP_PROP_FRAME_COUNT);
  result.frames_expected = result.has_sidecar    ? static_cast<int>(times.size())
                           : container_count > 0 ? static_cast<int>(container_count)
                                                 : 0;

  KeyframeSelector selector(options);
  const std::vector<int> png{cv::IMWRITE_PNG_COMPRESSION, video_options.png_compression};
  auto write = [&](const Keyframe& keyframe, double position_s) {
    IndexRow row;
    row.file = keyframeName(video, keyframe.frame);
    row.video = result.video;
    row.frame = keyframe.frame;
    if (result.has_sidecar && keyframe.frame < static_cast<int>(times.size())) {
      row.camera_time_s = times[static_cast<size_t>(keyframe.frame)].camera_time_s;
      row.sim_time_s = times[static_cast<size_t>(keyframe.frame)].sim_time_s;
    } else {
      row.camera_time_s = position_s;
    }
    row.sharpness = keyframe.sharpness;
    row.motion_px = keyframe.motion_px;
    row.tracked = keyframe.tracked;
    row.trigger = keyframe.trigger;
    const fs::path file = out_folder / row.file;
    if (!cv::imwrite(file.string(), keyframe.image, png)) {
      throw StageError(kStage, file.string() + ": cannot write the keyframe");
    }
    result.keyframes.push_back(std::move(row));
  };

  // Container timestamps for videos without a sidecar (frame index -> seconds).
  std::vector<double> positions;
  cv::Mat frame;
  for (;;) {
    bool ok = false;
    try {
      ok = capture.read(frame);
    } catch (const cv::Exception& e) {
      ok = false;
      result.problem =
          "decoding failed at frame " + std::to_string(result.frames_read) + ": " + e.err;
    }
    if (!ok || frame.empty()) break;
    if (!result.has_sidecar) positions.push_back(capture.get(cv::CAP_PROP_POS_MSEC) / 1000.0);
    const int index = result.frames_read++;
    if (index == 0 && !video_options.mask.empty()) {
      if (video_options.mask.size() != frame.size()) {
        throw StageError(kStage, video_options.mask_file + ": mask is " +
                                     std::to_string(video_options.mask.cols) + "x" +
                                     std::to_string(video_options.mask.rows) +
                                     " px but the frames of " + video.string() + " are " +
                                     std::to_string(frame.cols) + "x" + std::to_string(frame.rows) +
                                     " px");
      }
      selector.setMask(video_options.mask);
    }
    std::optional<Keyframe> keyframe;
    try {
      keyframe = selector.addFrame(index, frame);
    } catch (const std::invalid_argument& e) {  // a frame of another size or type
      throw StageError(kStage, video.string() + ": " + e.what());
    }
    if (keyframe) {
      write(*keyframe, result.has_sidecar ? 0 : positions[static_cast<size_t>(keyframe->frame)]);
    }
    if (on_frame) on_frame();
  }
  if (result.frames_read == 0) {
    throw StageError(kStage, video.string() + ": no frame could be decoded (damaged video)");
  }
  if (result.has_sidecar && result.frames_read > result.frames_expected) {
    throw StageError(kStage, video.string() + ": " + std::to_string(result.frames_read) +
                                 " frames decoded but its sidecar " +
                                 sidecarOf(video).filename().string() + " lists " +
                                 std::to_string(result.frames_expected) +
                                 " (not this video's sidecar?)");
  }
  if (result.frames_read < result.frames_expected) {
    std::string problem = "the video ends after " + std::to_string(result.frames_read) + " of " +
                          std::to_string(result.frames_expected) + " frames (" +
                          (result.has_sidecar ? "its sidecar's count" : "the container's count") +
                          "): truncated or damaged";
    if (!result.problem.empty()) problem += "; " + result.problem;
    if (!video_options.keep_damaged) {
      throw StageError(kStage, video.string() + ": " + problem +
                                   " (--keep-damaged keeps the keyframes read before the damage)");
    }
    result.problem = problem;
  } else if (!result.problem.empty() && !video_options.keep_damaged) {
    throw StageError(kStage, video.string() + ": " + result.problem);
  }
  if (auto keyframe = selector.finish()) {
    write(*keyframe, result.has_sidecar ? 0 : positions[static_cast<size_t>(keyframe->frame)]);
  }
  result.rejected = selector.rejected();
  result.counts = selector.counts();
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace auv::recon::keyframes
