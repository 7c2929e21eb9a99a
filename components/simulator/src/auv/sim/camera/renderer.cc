#include "auv/sim/camera/renderer.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <thread>

namespace auv::sim {
namespace {

constexpr float kMaxRange = 1000.0f;  // m; beyond a few tens of metres only veiling light remains
constexpr int kRowsPerBand = 8;

int threadCount(int requested) {
  if (requested > 0) return requested;
  return std::max(1u, std::thread::hardware_concurrency());
}

}  // namespace

cv::Mat renderRadiance(const CameraModel& camera,
                       const std::vector<Eigen::Isometry3d>& camera_to_world,
                       const ImageFormation& formation, const RayCaster& caster, int threads) {
  if (camera_to_world.empty()) throw std::invalid_argument("renderRadiance: no camera pose");
  const int width = camera.width(), height = camera.height(), spp = camera.samplesPerPixel();
  const std::vector<Eigen::Vector3f>& rays = camera.rays();
  const float weight = 1.0f / static_cast<float>(spp * camera_to_world.size());
  cv::Mat radiance(height, width, CV_32FC3, cv::Scalar::all(0));

  const int bands = (height + kRowsPerBand - 1) / kRowsPerBand;
  std::atomic<int> next_band{0};
  auto worker = [&]() {
    std::vector<Eigen::Vector3f> origins, directions;
    std::vector<RayHit> hits;
    for (int band = next_band++; band < bands; band = next_band++) {
      const int row_begin = band * kRowsPerBand;
      const int row_end = std::min(height, row_begin + kRowsPerBand);
      const size_t first = static_cast<size_t>(row_begin) * width * spp;
      const size_t count = static_cast<size_t>(row_end - row_begin) * width * spp;
      for (const Eigen::Isometry3d& pose : camera_to_world) {
        const Eigen::Matrix3f rotation = pose.linear().cast<float>();
        origins.assign(count, pose.translation().cast<float>());
        directions.resize(count);
        for (size_t i = 0; i < count; ++i) directions[i] = rotation * rays[first + i];
        caster.castMany(origins, directions, kMaxRange, hits, /*coherent=*/true);
        for (int row = row_begin; row < row_end; ++row) {
          cv::Vec3f* out = radiance.ptr<cv::Vec3f>(row);
          for (int col = 0; col < width; ++col) {
            const size_t base = (static_cast<size_t>(row - row_begin) * width + col) * spp;
            Eigen::Vector3f sum = Eigen::Vector3f::Zero();
            for (int s = 0; s < spp; ++s) {
              sum += formation.radiance(directions[base + s], hits[base + s], caster);
            }
            out[col] += cv::Vec3f(sum.x(), sum.y(), sum.z()) * weight;
          }
        }
      }
    }
  };
  const int workers = std::min(threadCount(threads), bands);
  std::vector<std::thread> pool;
  for (int i = 1; i < workers; ++i) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  return radiance;
}

cv::Mat renderFrame(const CameraModel& camera,
                    const std::vector<Eigen::Isometry3d>& camera_to_world,
                    const ImageFormation& formation, const RayCaster& caster, uint64_t noise_seed,
                    int threads) {
  const cv::Mat radiance = renderRadiance(camera, camera_to_world, formation, caster, threads);
  return developImage(radiance, camera.cosOffAxis(), camera.options(), noise_seed);
}

cv::Mat renderFrame(const CameraModel& camera, const Eigen::Isometry3d& camera_to_world,
                    const WaterOptics& water, const RayCaster& caster,
                    const IlluminationOptions& illumination, uint64_t noise_seed, int threads) {
  const ImageFormation formation = cameraImageFormation(camera.options(), water, illumination, {},
                                                        camera_to_world.translation());
  return renderFrame(camera, {camera_to_world}, formation, caster, noise_seed, threads);
}

std::vector<Eigen::Isometry3d> exposurePoses(const Trajectory& trajectory,
                                             const CameraModel& camera, double sim_time) {
  const CameraOptions& options = camera.options();
  const Eigen::Isometry3d mount = options.cameraToBody();
  auto poseAt = [&](double t) { return trajectory.poseAt(t) * mount; };
  if (options.exposure_time <= 0 || options.max_blur_samples <= 1) return {poseAt(sim_time)};

  // Exposure centred on the frame time; its camera-clock length is exposure_time.
  const double half = 0.5 * options.exposure_time;
  const Eigen::Isometry3d open = poseAt(sim_time - half), close = poseAt(sim_time + half);
  const double angle = Eigen::AngleAxisd(open.linear().transpose() * close.linear()).angle();
  const double shift = (close.translation() - open.translation()).norm();
  const double focal = std::max(camera.intrinsics().fx, camera.intrinsics().fy);
  const double motion_px = focal * (angle + shift / 1.5);
  // Below a pixel of motion blur is invisible; above, a sub-exposure every ~1.5 px keeps the
  // streak smooth without paying for one render per pixel.
  const int samples = motion_px < 1.0 ? 1
                                      : std::clamp(static_cast<int>(std::ceil(motion_px / 1.5)) + 1,
                                                   2, options.max_blur_samples);
  if (samples == 1) return {poseAt(sim_time)};
  std::vector<Eigen::Isometry3d> poses;
  for (int k = 0; k < samples; ++k) {
    poses.push_back(poseAt(sim_time - half + options.exposure_time * k / (samples - 1)));
  }
  return poses;
}

}  // namespace auv::sim
