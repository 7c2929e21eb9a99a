#pragma once
// One recorded video -> its keyframes on disk: streams the video through cv::VideoCapture
// (never loaded whole), feeds KeyframeSelector, writes each keyframe as PNG and returns the
// rows of index.csv / rejected.csv. Frame times come from the recording's sidecar
// `<video>.frames.csv` (header `frame,camera_time_s,sim_time_s`).

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "auv/recon/keyframes/selector.h"

namespace auv::recon::keyframes {

struct FrameTime {
  double camera_time_s = 0;
  std::optional<double> sim_time_s;  ///< empty in the sidecar: unknown
};

/// The frame-time sidecar of a recording. Throws StageError("keyframes", "<file>:<line>: ...")
/// for a wrong header, a malformed row or frames out of order.
std::vector<FrameTime> readFrameTimes(const std::filesystem::path& sidecar);

/// The video containers the keyframes stage reads (lower case, with the dot).
const std::vector<std::string>& videoExtensions();

/// `<video>.frames.csv` beside the video.
std::filesystem::path sidecarOf(const std::filesystem::path& video);

/// One line of keyframes/<camera>/index.csv.
struct IndexRow {
  std::string file;   ///< PNG name in the camera folder
  std::string video;  ///< video file name
  int frame = 0;
  double camera_time_s = 0;
  std::optional<double> sim_time_s;
  double sharpness = 0, motion_px = 0;
  int tracked = 0;
  Trigger trigger = Trigger::START;
};

struct VideoOptions {
  int png_compression = 1;  ///< cv::IMWRITE_PNG_COMPRESSION, 0-9 (1: fast, larger files)
  /// A video that ends before its sidecar's (or container's) frame count: false = stage
  /// failure naming the file; true = keep the keyframes read up to the damage and report it.
  bool keep_damaged = false;
  /// The camera's mask (masks/<camera>.png, 0: ignore; CV_8U of the frames' size) and its
  /// file, for the message when its size is not the frames'. Empty: none.
  cv::Mat mask;
  std::string mask_file;
};

struct VideoKeyframes {
  std::string video;  ///< file name
  int frames_read = 0;
  int frames_expected = 0;  ///< sidecar rows, else the container's count (0 unknown)
  double frame_rate = 0;    ///< Hz, the container's
  bool has_sidecar = false;
  std::string problem;  ///< damage kept with keep_damaged (empty: none)
  std::vector<IndexRow> keyframes;
  std::vector<RejectedFrame> rejected;
  SelectorCounts counts;
  double seconds = 0;  ///< wall time
};

/// Selects the keyframes of `video`, writing `<stem>_<frame, 6 digits>.png` into `out_folder`.
/// `on_frame` (optional) is called after every decoded frame (progress). Throws StageError
/// naming the video when it cannot be opened, decodes no frame, is damaged (unless
/// keep_damaged) or disagrees with its sidecar.
VideoKeyframes selectVideoKeyframes(const std::filesystem::path& video,
                                    const std::filesystem::path& out_folder,
                                    const KeyframeOptions& options,
                                    const VideoOptions& video_options,
                                    const std::function<void()>& on_frame = nullptr);

/// Frames of a video as the container (or sidecar, if present) states it; 0 when unknown.
int expectedFrameCount(const std::filesystem::path& video);

}  // namespace auv::recon::keyframes
