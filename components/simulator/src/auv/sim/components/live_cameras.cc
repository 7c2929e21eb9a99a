#include "auv/sim/components/live_cameras.h"

#include <opencv2/imgcodecs.hpp>
#include <stdexcept>

#include "auv/interfaces/msg_time.h"
#include "auv/sim/camera/camera_model.h"
#include "auv/sim/camera/renderer.h"

namespace auv::sim {

struct LiveCameras::Camera {
  const CameraOptions* options;
  std::unique_ptr<CameraModel> model;
  std::shared_ptr<interfaces::Publisher<msg::CompressedImage>> publisher;
  uint64_t frame = 0;
};

LiveCameras::LiveCameras(interfaces::Node& node, const Scenario& scenario, const RayCaster& world,
                         const LiveCameraOptions& options)
    : scenario_(scenario),
      world_(world),
      options_(options),
      rig_(CameraRig::fromScenario(scenario)),
      illumination_(IlluminationOptions::fromScenario(scenario)) {
  if (options_.rate == 0) return;
  for (const std::string& id : options_.cameras.empty() ? rig_.ids() : options_.cameras) {
    auto camera = std::make_unique<Camera>();
    try {
      camera->options = &rig_.camera(id);
    } catch (const std::invalid_argument&) {
      throw std::invalid_argument("camera_live_cameras: no camera '" + id + "' in the scenario");
    }
    camera->model = std::make_unique<CameraModel>(*camera->options, options_.scale);
    camera->publisher = node.createPublisher<msg::CompressedImage>("camera/" + id + "/compressed",
                                                                   interfaces::sensorDataQos());
    cameras_.push_back(std::move(camera));
  }
  thread_ = std::thread([this] { renderLoop(); });
}

LiveCameras::~LiveCameras() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void LiveCameras::offer(double sim_time, const Eigen::Isometry3d& body_to_world) {
  if (cameras_.empty() || sim_time < next_) return;
  next_ = sim_time + 1.0 / options_.rate;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (busy_) {
      ++skipped_;
      return;
    }
    busy_ = true;
    pending_time_ = sim_time;
    pending_pose_ = body_to_world;
  }
  wake_.notify_all();
}

void LiveCameras::renderLoop() {
  const std::vector<int> jpeg = {cv::IMWRITE_JPEG_QUALITY, options_.jpeg_quality};
  for (;;) {
    double t = 0;
    Eigen::Isometry3d body_to_world;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return busy_ || stopping_; });
      if (stopping_) return;
      t = pending_time_;
      body_to_world = pending_pose_;
    }
    for (auto& camera : cameras_) {
      const Eigen::Isometry3d camera_to_world = body_to_world * camera->options->cameraToBody();
      const ImageFormation formation =
          cameraImageFormation(*camera->options, scenario_.water, illumination_,
                               rig_.lightsInWorld(body_to_world), camera_to_world.translation());
      // One thread: the preview must not take the cores the vehicle's processes need.
      const cv::Mat frame = renderFrame(*camera->model, {camera_to_world}, formation, world_,
                                        camera->options->noise_seed + camera->frame++, 1);
      msg::CompressedImage image;
      image.header().stamp(interfaces::toMsgTime(static_cast<int64_t>(t * 1e9)));
      image.header().frame_id("camera_" + camera->options->id);
      image.format("jpeg");
      std::vector<uint8_t> bytes;
      cv::imencode(".jpg", frame, bytes, jpeg);
      image.data(std::move(bytes));
      camera->publisher->publish(image);
      ++published_;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    busy_ = false;
  }
}

}  // namespace auv::sim
