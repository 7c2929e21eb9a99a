#include "auv/sim/sensors/sensor_cloud.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace auv::sim {

size_t SensorCloud::returns() const {
  return static_cast<size_t>(
      std::count_if(intensities.begin(), intensities.end(), [](float i) { return i > 0.0f; }));
}

void castToSurfaces(const RayCaster& world, double seabed_depth, const Eigen::Vector3f& origin,
                    const std::vector<Eigen::Vector3f>& directions, float max_range,
                    std::vector<float>& distances, std::vector<float>& cos_incidence) {
  const size_t n = directions.size();
  std::vector<Eigen::Vector3f> origins(n, origin);
  std::vector<RayHit> hits(n);
  world.castMany(origins, directions, max_range, hits);
  distances.assign(n, std::numeric_limits<float>::infinity());
  cos_incidence.assign(n, 0.0f);
  const float below = static_cast<float>(seabed_depth) - origin.z();
  for (size_t i = 0; i < n; ++i) {
    if (hits[i].hit()) {
      distances[i] = hits[i].distance;
      cos_incidence[i] = std::abs(directions[i].dot(hits[i].normal));
    }
    // The seabed plane (normal up) when the ray points down from above it.
    if (below > 0.0f && directions[i].z() > 1e-6f) {
      const float t = below / directions[i].z();
      if (t <= max_range && t < distances[i]) {
        distances[i] = t;
        cos_incidence[i] = directions[i].z();
      }
    }
  }
}

void PingSchedule::fired(double time) {
  if (first_ || time - next_ >= period_ || time + 1e-9 < next_) {
    next_ = time + period_;
  } else {
    next_ += period_;
  }
  first_ = false;
}

SensorCloud BeamFan::ping(const Eigen::Isometry3d& mounting, const BeamReturnModel& model,
                          const Eigen::Isometry3d& body_pose_true, double time,
                          const RayCaster& world, double seabed_depth) {
  SensorCloud cloud;
  cloud.stamp = time;
  cloud.mounting = mounting;
  cloud.max_range = model.max_range;

  const Eigen::Isometry3d head_to_world = body_pose_true * mounting;
  const size_t n = directions_.size();
  world_directions_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    world_directions_[i] = (head_to_world.linear() * directions_[i]).normalized().cast<float>();
  }
  castToSurfaces(world, seabed_depth, head_to_world.translation().cast<float>(), world_directions_,
                 static_cast<float>(model.max_range), distances_, cos_incidence_);

  const double min_cos = std::cos(model.max_incidence) - 1e-9;
  cloud.points.reserve(n);
  cloud.intensities.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    // Drawn for every beam so that noise sequences do not depend on what was hit.
    const double noise = model.range_noise * normal_(rng_);
    const double distance = distances_[i];
    double range = SensorCloud::kNoReturnFactor * model.max_range;  // nothing within max_range
    float intensity = 0.0f;
    if (std::isfinite(distance)) {
      // Something is there: closer than the blanking distance, or hit too obliquely to echo,
      // the beam reports nothing, and is left out rather than sent as free water.
      if (distance < model.min_range || cos_incidence_[i] < min_cos) continue;
      range = std::clamp(distance + noise, model.min_range, model.max_range);
      intensity = std::max(1e-3f, cos_incidence_[i]);
    }
    cloud.points.push_back((mounting * (range * directions_[i])).cast<float>());
    cloud.intensities.push_back(intensity);
  }
  return cloud;
}

}  // namespace auv::sim
