#pragma once
// Ray-traced camera frames: one Embree ray per pixel sample (castMany over bands of rows,
// bands spread over threads), shaded with the underwater image formation model, then
// developed by the sensor model into the 8-bit BGR frame the camera records.

#include <Eigen/Geometry>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "auv/sim/camera/camera_model.h"
#include "auv/sim/camera/image_formation.h"
#include "auv/sim/camera/trajectory.h"
#include "auv/sim/raycast/ray_caster.h"

namespace auv::sim {

/// Linear RGB radiance (CV_32FC3, channels R, G, B) seen by `camera`: each pixel is the mean
/// over the model's sub-pixel rays and over the sub-exposure poses `camera_to_world` (one pose
/// = an instantaneous exposure). `threads` <= 0 uses every core.
cv::Mat renderRadiance(const CameraModel& camera,
                       const std::vector<Eigen::Isometry3d>& camera_to_world,
                       const ImageFormation& formation, const RayCaster& caster, int threads = 0);

/// renderRadiance + developImage (vignetting, exposure, sRGB, noise): CV_8UC3 BGR.
cv::Mat renderFrame(const CameraModel& camera,
                    const std::vector<Eigen::Isometry3d>& camera_to_world,
                    const ImageFormation& formation, const RayCaster& caster, uint64_t noise_seed,
                    int threads = 0);

/// One instantaneous frame in the scenario's water under the given daylight, no lights, with
/// the camera's exposure settings (cameraImageFormation).
cv::Mat renderFrame(const CameraModel& camera, const Eigen::Isometry3d& camera_to_world,
                    const WaterOptics& water, const RayCaster& caster,
                    const IlluminationOptions& illumination = {}, uint64_t noise_seed = 0,
                    int threads = 0);

/// Camera poses (camera -> world) spread evenly over the exposure of a frame taken at
/// `sim_time`, for motion blur: one every ~1.5 px of image motion (estimated from the rotation
/// and, for a scene ~1.5 m away, the translation), at most the camera's max_blur_samples; one
/// pose when the motion stays under a pixel or the exposure time is 0.
std::vector<Eigen::Isometry3d> exposurePoses(const Trajectory& trajectory,
                                             const CameraModel& camera, double sim_time);

}  // namespace auv::sim
