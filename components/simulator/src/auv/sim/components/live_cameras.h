#pragma once
// Live camera frames for viewers: the scenario's cameras rendered from the true pose at a low
// rate and published as JPEG on `camera/<id>/compressed` (CompressedImage, sensor_data), so a
// Foxglove client or `auv view` shows what the vehicle films while the mission runs. The
// survey's frames stay those `auv sim render` draws afterwards at full rate and quality: these
// are a preview. Rendering runs on a thread of its own and never holds the physics loop up; a
// frame that falls due while the previous one renders is skipped (components/simulator/
// README.md, "Live camera frames").

#include <Eigen/Geometry>
#include <atomic>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "auv/interfaces/node.h"
#include "auv/sim/camera/camera_rig.h"
#include "auv/sim/camera/image_formation.h"
#include "auv/sim/raycast/ray_caster.h"
#include "auv/sim/world/scenario.h"

namespace auv::sim {

struct LiveCameraOptions {
  double rate = 0.0;                 ///< Hz of simulated time per camera; 0: no live frames
  double scale = 0.25;               ///< resolution factor of the cameras' own size
  int jpeg_quality = 80;             ///< [1, 100]
  std::vector<std::string> cameras;  ///< ids to publish; empty: all of the scenario's
};

class LiveCameras {
 public:
  /// Creates one publisher per camera (the options are the simulator's, checked there); an
  /// unknown camera id throws std::invalid_argument naming it.
  LiveCameras(interfaces::Node& node, const Scenario& scenario, const RayCaster& world,
              const LiveCameraOptions& options);
  ~LiveCameras();
  LiveCameras(const LiveCameras&) = delete;
  LiveCameras& operator=(const LiveCameras&) = delete;

  /// Called by the physics loop every step with the true body pose (FRD -> NED): starts a
  /// frame when one is due and the renderer is idle.
  void offer(double sim_time, const Eigen::Isometry3d& body_to_world);
  uint64_t published() const { return published_.load(); }
  uint64_t skipped() const { return skipped_.load(); }

 private:
  struct Camera;
  void renderLoop();

  const Scenario& scenario_;
  const RayCaster& world_;
  LiveCameraOptions options_;
  CameraRig rig_;
  IlluminationOptions illumination_;
  std::vector<std::unique_ptr<Camera>> cameras_;
  double next_ = 0.0;

  std::mutex mutex_;
  std::condition_variable wake_;
  bool busy_ = false, stopping_ = false;
  double pending_time_ = 0.0;
  Eigen::Isometry3d pending_pose_ = Eigen::Isometry3d::Identity();
  std::atomic<uint64_t> published_{0}, skipped_{0};
  std::thread thread_;
};

}  // namespace auv::sim
