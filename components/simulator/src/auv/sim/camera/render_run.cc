#include "auv/sim/camera/render_run.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <mutex>
#include <ostream>
#include <sstream>
#include <thread>

#include "auv/sim/camera/camera_rig.h"
#include "auv/sim/camera/colmap_ground_truth.h"
#include "auv/sim/camera/renderer.h"
#include "auv/sim/camera/trajectory.h"
#include "auv/sim/raycast/ray_caster.h"
#include "auv/sim/world/change_truth.h"
#include "auv/sim/world/scenario.h"

namespace auv::sim {
namespace fs = std::filesystem;
namespace {

using Clock = std::chrono::steady_clock;

// Renders frames on `threads` workers and hands them to `consume` in frame order. At most
// 2 x threads frames wait in memory.
template <typename Render, typename Consume>
void renderInOrder(int64_t count, int threads, Render render, Consume consume) {
  if (threads <= 1) {
    for (int64_t i = 0; i < count; ++i) consume(i, render(i));
    return;
  }
  std::mutex mutex;
  std::condition_variable changed;
  std::map<int64_t, cv::Mat> done;
  int64_t next_to_render = 0, next_to_write = 0;
  std::exception_ptr failure;
  auto worker = [&]() {
    while (true) {
      int64_t index;
      {
        std::unique_lock<std::mutex> lock(mutex);
        changed.wait(lock, [&] {
          return failure || next_to_render >= count || next_to_render < next_to_write + 2 * threads;
        });
        if (failure || next_to_render >= count) return;
        index = next_to_render++;
      }
      try {
        cv::Mat frame = render(index);
        std::lock_guard<std::mutex> lock(mutex);
        done.emplace(index, std::move(frame));
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex);
        if (!failure) failure = std::current_exception();
      }
      changed.notify_all();
    }
  };
  std::vector<std::thread> pool;
  for (int i = 0; i < threads; ++i) pool.emplace_back(worker);
  try {
    while (next_to_write < count) {
      cv::Mat frame;
      {
        std::unique_lock<std::mutex> lock(mutex);
        changed.wait(lock, [&] { return failure || done.count(next_to_write) > 0; });
        if (failure) break;
        frame = std::move(done[next_to_write]);
        done.erase(next_to_write);
      }
      consume(next_to_write, frame);
      {
        std::lock_guard<std::mutex> lock(mutex);
        ++next_to_write;
      }
      changed.notify_all();
    }
  } catch (...) {
    std::lock_guard<std::mutex> lock(mutex);
    if (!failure) failure = std::current_exception();
  }
  changed.notify_all();
  for (std::thread& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
}

std::string formatSeconds(double seconds) {
  const int s = static_cast<int>(std::lround(seconds));
  std::ostringstream out;
  if (s >= 3600) out << s / 3600 << "h";
  if (s >= 60) out << (s / 60) % 60 << "m";
  out << s % 60 << "s";
  return out.str();
}

}  // namespace

void RenderRunOptions::check() const {
  if (!(scale > 0 && scale <= 8)) {
    throw std::invalid_argument("scale: expected a factor in (0, 8], got " + std::to_string(scale));
  }
  if (max_frames < 0) throw std::invalid_argument("max frames: expected >= 0");
  if (threads > 1024) throw std::invalid_argument("threads: expected <= 1024");
  if (!(progress_interval > 0)) {
    throw std::invalid_argument("progress interval: expected seconds > 0, got " +
                                std::to_string(progress_interval));
  }
  if (std::isnan(start_time) || std::isnan(end_time) || !(end_time >= start_time)) {
    throw std::invalid_argument("time span: expected start <= end");
  }
}

std::vector<FrameStamp> cameraFrameTimes(const CameraOptions& camera, double start_sim_time,
                                         double end_sim_time, int64_t max_frames) {
  std::vector<FrameStamp> frames;
  const double first_camera_time = camera.cameraTime(start_sim_time);
  for (int64_t k = 0; max_frames <= 0 || k < max_frames; ++k) {
    FrameStamp stamp;
    stamp.frame = k;
    stamp.camera_time = first_camera_time + static_cast<double>(k) / camera.frame_rate;
    stamp.sim_time = camera.simTime(stamp.camera_time);
    if (stamp.sim_time > end_sim_time + 1e-9) break;
    frames.push_back(stamp);
  }
  return frames;
}

std::string cameraVideoPath(const std::string& run_dir, const std::string& camera) {
  return (fs::path(run_dir) / "vehicle" / "recordings" / camera / (camera + "_0001.mp4")).string();
}

RenderRunReport renderRun(const std::string& run_dir, const RenderRunOptions& options) {
  options.check();
  if (!fs::is_directory(run_dir)) throw ConfigError(run_dir + ": no such run folder");
  const std::string scenario_path = (fs::path(run_dir) / "scenario.yaml").string();
  if (!fs::is_regular_file(scenario_path)) {
    throw ConfigError(scenario_path + ": no such file (is " + run_dir + " a run folder?)");
  }
  const std::string trajectory_path =
      (fs::path(run_dir) / "ground_truth" / "trajectory.tum").string();
  if (!fs::is_regular_file(trajectory_path)) {
    throw ConfigError(trajectory_path + ": no such file (the run logged no ground truth)");
  }
  const Scenario scenario = loadScenario(scenario_path);
  const CameraRig rig = CameraRig::fromScenario(scenario);
  const IlluminationOptions illumination = IlluminationOptions::fromScenario(scenario);
  const Trajectory trajectory = Trajectory::load(trajectory_path);

  std::vector<const CameraOptions*> selected;
  for (const std::string& id : options.cameras.empty() ? rig.ids() : options.cameras) {
    selected.push_back(&rig.camera(id));  // throws std::invalid_argument for an unknown id
  }
  const double start = std::max(options.start_time, trajectory.startTime());
  const double end = std::min(options.end_time, trajectory.endTime());
  if (!(end >= start)) {
    throw std::invalid_argument("time span: the run's trajectory covers [" +
                                std::to_string(trajectory.startTime()) + ", " +
                                std::to_string(trajectory.endTime()) + "] s");
  }
  const Mesh mesh = loadWorldMesh(scenario);
  const RayCaster caster(mesh, scenario.surface_detail);
  const int threads =
      options.threads > 0 ? options.threads : std::max(1u, std::thread::hardware_concurrency());

  const fs::path truth_dir = fs::path(run_dir) / "ground_truth";
  // A later visit of a changing site: the true change, for `auv recon evaluate`.
  if (writeScenarioChangeTruth(scenario, truth_dir.string()) && options.log)
    *options.log << "render: " << scenario.changes.size() << " site changes -> "
                 << (truth_dir / "changes.json").string() << "\n";
  std::map<int, std::string> camera_names, camera_lines;
  for (size_t i = 0; i < rig.cameras.size(); ++i) camera_names[i + 1] = rig.cameras[i].id;

  RenderRunReport report;
  for (const CameraOptions* options_ptr : selected) {
    const CameraOptions& camera_options = *options_ptr;
    const int camera_id = static_cast<int>(options_ptr - rig.cameras.data()) + 1;
    const CameraModel camera(camera_options, options.scale);
    const std::vector<FrameStamp> stamps =
        cameraFrameTimes(camera_options, start, end, options.max_frames);
    const std::string video_path = cameraVideoPath(run_dir, camera_options.id);
    const std::string video_name = fs::path(video_path).filename().string();
    if (options.log) {
      *options.log << "render: " << camera_options.id << ": " << stamps.size() << " frames "
                   << camera.width() << "x" << camera.height() << " at "
                   << camera_options.frame_rate << " fps -> " << video_path << "\n";
    }
    VideoRecorder recorder(video_path, camera_options.frame_rate,
                           cv::Size(camera.width(), camera.height()), options.log);
    const std::string images_path = (truth_dir / ("images_" + camera_options.id + ".txt")).string();
    const std::string images_temp = images_path + ".incomplete";
    fs::create_directories(truth_dir);
    std::ofstream images(images_temp);
    images << "# Image list with two lines of data per image:\n"
              "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
              "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
              "# Ground truth of camera "
           << camera_options.id << " (world NED -> camera), NAME = <video>#<frame>\n"
           << "# Number of images: " << stamps.size() << "\n";

    const auto started = Clock::now();
    auto last_report = started;
    auto render = [&](int64_t index) {
      const FrameStamp& stamp = stamps[index];
      const std::vector<Eigen::Isometry3d> poses =
          exposurePoses(trajectory, camera, stamp.sim_time);
      const Eigen::Isometry3d body_to_world = trajectory.poseAt(stamp.sim_time);
      const ImageFormation formation = cameraImageFormation(
          camera_options, scenario.water, illumination, rig.lightsInWorld(body_to_world),
          (body_to_world * camera_options.cameraToBody()).translation());
      return renderFrame(camera, poses, formation, caster,
                         frameSeed(camera_options.noise_seed, stamp.frame), 1);
    };
    auto consume = [&](int64_t index, const cv::Mat& frame) {
      const FrameStamp& stamp = stamps[index];
      recorder.write(frame, stamp.camera_time, stamp.sim_time);
      const Eigen::Isometry3d camera_to_world =
          trajectory.poseAt(stamp.sim_time) * camera_options.cameraToBody();
      images << colmapImageEntry(camera_id * 1000000LL + stamp.frame + 1, camera_to_world,
                                 camera_id, video_name + "#" + std::to_string(stamp.frame));
      const auto now = Clock::now();
      const bool last = index + 1 == static_cast<int64_t>(stamps.size());
      if (options.log &&
          (last || now - last_report > std::chrono::duration<double>(options.progress_interval))) {
        last_report = now;
        const double elapsed = std::chrono::duration<double>(now - started).count();
        const double fps = (index + 1) / std::max(elapsed, 1e-6);
        std::ostringstream line;  // own stream: leave the log's number format alone
        line << "render: " << camera_options.id << ": " << index + 1 << "/" << stamps.size()
             << " frames, " << std::fixed << std::setprecision(2) << fps << " fps";
        if (!last) line << ", " << formatSeconds((stamps.size() - index - 1) / fps) << " left";
        *options.log << line.str() << std::endl;
      }
    };
    try {
      renderInOrder(static_cast<int64_t>(stamps.size()), threads, render, consume);
      images.close();
      if (!images) throw std::runtime_error(images_temp + ": cannot write");
      recorder.finish();
    } catch (...) {
      images.close();
      std::error_code ignored;
      fs::remove(images_temp, ignored);
      throw;
    }
    fs::rename(images_temp, images_path);
    camera_lines[camera_id] = colmapCameraLine(camera_id, camera.intrinsics());
    updateColmapCameras((truth_dir / "cameras.txt").string(), camera_lines, camera_names);

    RenderedVideo video;
    video.camera = camera_options.id;
    video.video_path = video_path;
    video.fourcc = recorder.fourcc();
    video.frames = recorder.frames();
    if (!stamps.empty()) {
      video.first_sim_time = stamps.front().sim_time;
      video.last_sim_time = stamps.back().sim_time;
    }
    report.videos.push_back(video);
  }
  return report;
}

}  // namespace auv::sim
