#pragma once
// A forward-looking multibeam sonar (Blueview / Oculus class, as added to Sparus II for 3-D
// inspection): a fan of beams across a horizontal aperture, in a few rows over a vertical
// aperture, mounted pitched down so the fan sweeps the rock ahead and the seabed in front of the
// vehicle. Each ping casts one ray per beam into the *true* world (the mesh and the flat seabed
// beyond it), keeps the first return within [min_range, max_range] unless it grazes the
// surface beyond max_incidence, adds range noise, and reports the points in the body frame.
// Published on `sonar/scan`; the mapping component inserts each ping as rays from the head.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "auv/sim/common/yaml_section.h"
#include "auv/sim/raycast/ray_caster.h"
#include "auv/sim/sensors/sensor_cloud.h"

namespace auv::sim {

/// The scenario's `multibeam:` section (absent, or `enabled: false`: the vehicle has none).
/// Angles are radians here; YAML gives them in degrees under `<name>_deg` keys.
struct MultibeamOptions {
  bool enabled = false;  ///< a section without `enabled` enables the sensor
  /// m, head position on the body (FRD): under the nose.
  Eigen::Vector3d mount_position{0.6, 0.0, 0.15};
  double mount_pitch =
      25.0 * M_PI / 180.0;  ///< rad, fan axis below the horizontal (YAML pitch_deg)
  double mount_yaw = 0.0;   ///< rad, fan axis yaw on the body (YAML yaw_deg)

  int beams = 256;                                    ///< beams across the fan, per row
  int rows = 4;                                       ///< rows over the vertical aperture
  double horizontal_aperture = 120.0 * M_PI / 180.0;  ///< rad, first to last beam of a row
  double vertical_aperture = 20.0 * M_PI / 180.0;     ///< rad, first to last row (rows > 1)
  double rate = 10.0;                                 ///< Hz, pings
  double min_range = 0.5;                             ///< m, blanking
  double max_range = 30.0;                            ///< m
  double range_noise = 0.05;                          ///< m, sigma added to each return
  /// rad, returns from surfaces hit more obliquely than this (from the normal) are too weak
  /// to detect: the beam is left out of the ping (YAML max_incidence_deg).
  double max_incidence = 85.0 * M_PI / 180.0;
  double sound_speed = 1500.0;  ///< m/s, bounds the rate (two-way travel to max_range)

  /// Sonar head frame (x the fan's axis, y starboard, z down) -> body (FRD).
  Eigen::Isometry3d mounting() const;
  /// Throws ConfigError naming the field ("multibeam.<key>") when a value is out of range.
  void check() const;
  /// Reads the `multibeam:` section strictly (unknown keys are errors), then check() when
  /// enabled; errors name the file and the field. `present`: the scenario has the section (an
  /// empty `multibeam:` enables the sensor with the defaults).
  static MultibeamOptions fromYaml(const YamlSection& section, bool present);
  /// The `multibeam:` section of a scenario file's root.
  static MultibeamOptions fromScenario(const YamlSection& root) {
    const YAML::Node& node = root.node();
    return fromYaml(root.child("multibeam"), node.IsMap() && node["multibeam"].IsDefined());
  }
};

class Multibeam {
 public:
  /// Throws ConfigError when the options are invalid.
  Multibeam(const MultibeamOptions& options, uint64_t seed);

  bool due(double time) const { return schedule_.due(time); }
  /// Pings at `time` from the vehicle's true pose (body FRD -> world NED) into `world` and the
  /// seabed plane at `seabed_depth`, and schedules the next ping.
  SensorCloud ping(const Eigen::Isometry3d& body_pose_true, double time, const RayCaster& world,
                   double seabed_depth);

  /// Unit beam directions in the head frame, row by row (index row * beams + beam), rows from
  /// the upper edge of the vertical aperture down, beams from port to starboard.
  const std::vector<Eigen::Vector3d>& beamDirections() const { return fan_.directions(); }
  const MultibeamOptions& options() const { return options_; }

 private:
  MultibeamOptions options_;
  PingSchedule schedule_;
  BeamFan fan_;
};

}  // namespace auv::sim
