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

}  // namespace auv::sim
