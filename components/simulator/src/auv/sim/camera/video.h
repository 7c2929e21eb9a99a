#pragma once
// Writes a camera's video as the GoPro on the vehicle would leave it on its card: an H.264 MP4
// (OpenCV VideoWriter through FFmpeg, fourcc avc1; mp4v with a warning where H.264 is not
// available) plus a sidecar "<video>.frames.csv" with one row per frame:
//   frame,camera_time_s,sim_time_s
// (frame from 0; camera_time_s on the camera's own clock; sim_time_s the simulation time the
// frame shows, which a real camera would not know: ground truth for evaluation).
// Both are written under temporary names and renamed into place only by finish(), so a
// failed or interrupted recording never appears under the final name.

#include <cstdint>
#include <fstream>
#include <iosfwd>
#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>
#include <string>
#include <vector>

namespace auv::sim {

/// One row of a frames sidecar.
struct FrameStamp {
  int64_t frame = 0;
  double camera_time = 0;  ///< s, camera clock
  double sim_time = 0;     ///< s, simulation clock
};

class VideoRecorder {
 public:
  /// Creates the folder if needed and opens "<stem>.incomplete.mp4" beside `path` (which
  /// should end in .mp4). Throws std::runtime_error naming the file if no encoder opens.
  /// Warnings (codec fallback) go to `log` when given.
  VideoRecorder(const std::string& path, double fps, cv::Size frame_size,
                std::ostream* log = nullptr);
  /// Without finish(): closes and deletes the temporary files.
  ~VideoRecorder();
  VideoRecorder(const VideoRecorder&) = delete;
  VideoRecorder& operator=(const VideoRecorder&) = delete;

  /// Appends a CV_8UC3 BGR frame of the recorder's size (anything else throws
  /// std::invalid_argument: OpenCV would drop it silently) and its sidecar row.
  void write(const cv::Mat& bgr, double camera_time, double sim_time);
  /// Closes the files and renames sidecar, then video, to their final names. Throws
  /// std::runtime_error (and removes the temporary files) if nothing was written or the
  /// encoder left no file.
  void finish();

  const std::string& path() const { return path_; }
  const std::string& fourcc() const { return fourcc_; }  ///< "avc1" or "mp4v"
  int64_t frames() const { return frames_; }

  static std::string sidecarPath(const std::string& video_path) {
    return video_path + ".frames.csv";
  }

 private:
  void discard() noexcept;

  std::string path_, temp_path_, sidecar_temp_path_;
  std::string fourcc_;
  cv::Size size_;
  cv::VideoWriter writer_;
  std::ofstream sidecar_;
  int64_t frames_ = 0;
  bool finished_ = false;
};

/// Reads a frames sidecar; throws std::runtime_error naming the file and line.
std::vector<FrameStamp> readFrameSidecar(const std::string& path);

}  // namespace auv::sim
