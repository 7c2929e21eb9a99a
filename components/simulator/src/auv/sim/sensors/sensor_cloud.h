#pragma once
// What the simulator's ranging sensors with several fixed beams (the forward-looking multibeam,
// the DVL's four beams) return each ping: one point per beam in the body frame, published as a
// PointCloud (idl/msg/sensors.idl) that the mapping component inserts as rays.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <random>
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

/// Fires pings at a fixed rate in simulation time; the first call is always due. When the
/// caller falls a whole period behind, missed pings are dropped rather than burst.
class PingSchedule {
 public:
  explicit PingSchedule(double rate) : period_(1.0 / rate) {}
  bool due(double time) const { return time + 1e-9 >= next_; }
  /// Marks a ping at `time` and schedules the next one.
  void fired(double time);
  double next() const { return next_; }

 private:
  double period_;
  double next_ = -1e300;
  bool first_ = true;
};

/// What a beam reports of the first surface it meets.
struct BeamReturnModel {
  double min_range = 0.0;    ///< m, blanking: a closer surface is left out of the ping
  double max_range = 0.0;    ///< m
  double range_noise = 0.0;  ///< m, sigma added to each return
  /// rad from the surface normal; a more oblique hit is too weak to echo and is left out.
  double max_incidence = 0.5 * M_PI;
};

/// A fixed set of beams in a sensor head (the multibeam's fan, the DVL's four beams): each ping
/// casts them into the true world and reports the first returns as a SensorCloud. Owns the
/// noise generator and the scratch buffers reused across pings.
class BeamFan {
 public:
  /// `directions`: unit vectors in the head frame.
  BeamFan(std::vector<Eigen::Vector3d> directions, uint64_t seed)
      : directions_(std::move(directions)), rng_(seed) {}

  /// One ping from the vehicle's true pose (body FRD -> world NED) with the head at `mounting`
  /// (head -> body), into `world` and the seabed plane at `seabed_depth`.
  SensorCloud ping(const Eigen::Isometry3d& mounting, const BeamReturnModel& model,
                   const Eigen::Isometry3d& body_pose_true, double time, const RayCaster& world,
                   double seabed_depth);
  const std::vector<Eigen::Vector3d>& directions() const { return directions_; }

 private:
  std::vector<Eigen::Vector3d> directions_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::vector<Eigen::Vector3f> world_directions_;
  std::vector<float> distances_, cos_incidence_;
};

}  // namespace auv::sim
