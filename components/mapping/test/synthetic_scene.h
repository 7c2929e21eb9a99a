#pragma once
// Synthetic sites for the prior map alignment tests (NED: z down, the seabed at z = 8 m): a small
// canyon with wavy walls and boulders, one straight wall, a field of pillars. A sonar fan is
// ray-marched against them (0.05 m steps, then bisection to 1 mm), so the returns are exact
// surface points seen from a pose, with the occlusions a real sonar has.

#include <Eigen/Geometry>
#include <cmath>
#include <vector>

#include "auv/mapping/map_builder.h"

namespace auv::mapping::test {

struct Sphere {
  Eigen::Vector3d centre;
  double radius;
};

struct Pillar {  // vertical cylinder standing on the seabed
  Eigen::Vector2d centre;
  double radius;
};

struct Scene {
  double seabed_z = 8.0;
  bool canyon = false;           // walls at y ~ +-7 m, wavy so that they also fix x a little
  bool straight_wall = false;    // one plane y = 6 + 0.15 x (not along the grid)
  std::vector<Sphere> boulders;  // seabed boulders
  std::vector<Pillar> pillars;

  bool solid(const Eigen::Vector3d& p) const {
    if (p.z() >= seabed_z) return true;
    if (canyon) {
      if (p.y() >= 7.0 + 0.8 * std::sin(2.0 * M_PI * p.x() / 13.0)) return true;
      if (p.y() <= -7.0 - 0.7 * std::sin(2.0 * M_PI * p.x() / 9.0 + 1.0)) return true;
    }
    if (straight_wall && p.y() >= 6.0 + 0.15 * p.x()) return true;
    for (const Sphere& s : boulders) {
      if ((p - s.centre).squaredNorm() <= s.radius * s.radius) return true;
    }
    for (const Pillar& c : pillars) {
      if ((p.head<2>() - c.centre).squaredNorm() <= c.radius * c.radius) return true;
    }
    return false;
  }

  /// Range of the first surface along a unit ray, or a negative value for none in max_range.
  double cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
              double max_range) const {
    constexpr double kStep = 0.05;
    for (double t = kStep; t <= max_range; t += kStep) {
      if (!solid(origin + t * direction)) continue;
      double low = t - kStep, high = t;
      for (int i = 0; i < 16; ++i) {
        const double mid = 0.5 * (low + high);
        (solid(origin + mid * direction) ? high : low) = mid;
      }
      return high;
    }
    return -1.0;
  }
};

/// The canyon of the tests: boulders on the seabed along it.
inline Scene canyonScene() {
  Scene scene;
  scene.canyon = true;
  scene.boulders = {{{-17.0, 2.5, 7.2}, 1.6}, {{-10.3, -3.1, 7.0}, 2.0}, {{-3.7, 3.9, 7.4}, 1.3},
                    {{2.2, -1.2, 7.1}, 1.5},  {{8.9, 2.7, 6.9}, 2.1},    {{15.4, -3.6, 7.3}, 1.4},
                    {{21.0, 1.4, 7.0}, 1.8}};
  return scene;
}

/// A sonar fan at `origin`: returns (surface points) and, for rays without one, a point at 1.5
/// max_range (free space only, as the simulator sends them). World frame.
struct Fan {
  std::vector<Eigen::Vector3d> points;
  std::vector<bool> is_return;
};

inline Fan castFan(const Scene& scene, const Eigen::Vector3d& origin, double max_range = 20.0,
                   double azimuth_step_deg = 3.0, double elevation_step_deg = 13.0) {
  Fan fan;
  for (double elevation = -20.0; elevation <= 60.0; elevation += elevation_step_deg) {
    for (double azimuth = 0.0; azimuth < 360.0; azimuth += azimuth_step_deg) {
      const double e = elevation * M_PI / 180.0, a = azimuth * M_PI / 180.0;
      // A little offset per row so that rows do not sample the same azimuths.
      const double a_row = a + 0.37 * e;
      const Eigen::Vector3d direction(std::cos(e) * std::cos(a_row), std::cos(e) * std::sin(a_row),
                                      std::sin(e));  // positive elevation looks down (NED)
      const double range = scene.cast(origin, direction, max_range);
      fan.is_return.push_back(range > 0.0);
      fan.points.push_back(origin + (range > 0.0 ? range : 1.5 * max_range) * direction);
    }
  }
  return fan;
}

/// A first visit: fans every `step` m along x at (x, y, z), inserted into a map as clouds.
inline void mapVisit(MapBuilder& builder, const Scene& scene, double x_from, double x_to,
                     double y = 0.0, double z = 3.0, double step = 1.0) {
  for (double x = x_from; x <= x_to + 1e-9; x += step) {
    const Eigen::Vector3d origin(x, y, z);
    builder.insertCloud(castFan(scene, origin).points, origin, 20.0);
  }
}

}  // namespace auv::mapping::test
