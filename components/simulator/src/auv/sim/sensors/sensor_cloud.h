#pragma once
// What the simulator's ranging sensors with several fixed beams (the forward-looking multibeam,
// the DVL's four beams) return each ping: one point per beam in the body frame, published as a
// PointCloud (idl/msg/sensors.idl) that the mapping component inserts as rays.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "auv/sim/raycast/ray_caster.h"

namespace auv::sim {

/// One ping of a multi-beam ranging sensor, in the body frame (FRD, "base_link").
struct SensorCloud {
  double stamp = 0.0;                                          ///< s
  Eigen::Isometry3d mounting = Eigen::Isometry3d::Identity();  ///< sensor -> body
  double max_range = 0.0;                                      ///< m
  /// m, body frame. A beam that met nothing within max_range is a point at
  /// kNoReturnFactor * max_range along the beam with intensity 0: past max_range, so mapping
  /// clears free space up to max_range and marks nothing occupied (PointCloud.max_range). A
  /// beam that met a surface it could not report (closer than min_range, or for the multibeam
  /// too oblique) is left out: it did not see free water.
  std::vector<Eigen::Vector3f> points;
  std::vector<float> intensities;  ///< 0..1 per point (cos of the incidence angle; 0 = none)

  static constexpr double kNoReturnFactor = 1.5;
  /// Number of points that are returns (intensity > 0).
  size_t returns() const;
};

/// The first surface along each ray from `origin` (world NED): the mesh or the flat seabed at
/// `seabed_depth` (the world beyond the mesh, as the altitude and hull contact see it).
/// `distances[i]` is infinity without a hit within `max_range`; `cos_incidence[i]` the cosine
/// between ray and surface normal (1 = perpendicular). `directions` are unit vectors.
void castToSurfaces(const RayCaster& world, double seabed_depth, const Eigen::Vector3f& origin,
                    const std::vector<Eigen::Vector3f>& directions, float max_range,
                    std::vector<float>& distances, std::vector<float>& cos_incidence);

}  // namespace auv::sim
