#pragma once
// Renders the camera videos of a finished simulated mission from its run folder:
//
//   <run>/scenario.yaml                        world, water, `cameras:` (read)
//   <run>/ground_truth/trajectory.tum          true body pose over time (read)
//   <run>/vehicle/recordings/<camera>/<camera>_0001.mp4 (+ .frames.csv)   (written)
//   <run>/ground_truth/cameras.txt, images_<camera>.txt                   (written, COLMAP)
//
// Each camera films at its frame rate on its own clock (camera_model.h) over the
// trajectory's time span; the camera pose is body pose x mounting. Frames are rendered in
// parallel and written in order; every output appears under its final name only when complete.

#include <cstdint>
#include <iosfwd>
#include <limits>
#include <string>
#include <vector>

#include "auv/sim/camera/camera_model.h"
#include "auv/sim/camera/video.h"

namespace auv::sim {

struct RenderRunOptions {
  std::vector<std::string> cameras;  ///< ids to render; empty = every camera of the rig
  int threads = 0;                   ///< frames rendered at once; <= 0 = every core
  double scale = 1.0;                ///< resolution factor (0, 8] (intrinsics scale along)
  int64_t max_frames = 0;            ///< per camera, 0 = all
  double start_time = -std::numeric_limits<double>::infinity();  ///< s sim, clipped to the run
  double end_time = std::numeric_limits<double>::infinity();     ///< s sim, clipped to the run
  std::ostream* log = nullptr;     ///< progress and warnings ("render: ..."), or none
  double progress_interval = 2.0;  ///< s of wall time between progress lines, > 0

  /// Throws std::invalid_argument naming the option.
  void check() const;
};

struct RenderedVideo {
  std::string camera;
  std::string video_path;
  std::string fourcc;  ///< avc1 (H.264) or mp4v
  int64_t frames = 0;
  double first_sim_time = 0, last_sim_time = 0;  ///< s
};

struct RenderRunReport {
  std::vector<RenderedVideo> videos;
};

/// When a camera takes its frames between two simulation times: evenly spaced on its own
/// clock (1 / frame_rate), the first at `start_sim_time`; at most `max_frames` (0 = no limit).
std::vector<FrameStamp> cameraFrameTimes(const CameraOptions& camera, double start_sim_time,
                                         double end_sim_time, int64_t max_frames = 0);

/// The video of `camera` in a run folder.
std::string cameraVideoPath(const std::string& run_dir, const std::string& camera);

/// Renders the videos. Throws ConfigError naming the file for a missing or bad scenario,
/// trajectory or mesh; std::invalid_argument for bad options or an unknown camera id;
/// std::runtime_error when a video cannot be written.
RenderRunReport renderRun(const std::string& run_dir, const RenderRunOptions& options);

}  // namespace auv::sim
