#pragma once
// The DVL's four acoustic beams as bottom returns. A Janus DVL (Teledyne / Nortek / LinkQuest
// class, as on Sparus II) sends four beams tilted ~30 deg from the vertical at 45, 135, 225 and
// 315 deg azimuth; where each beam meets the bottom is a range measurement the mapping inserts
// as a ray, so the seabed and rock below the vehicle enter the map. The scalar altitude of
// nav/odometry (used by the controller) is unchanged; this is an extra output of the same
// instrument, published on `dvl/beams`.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "auv/sim/common/yaml_section.h"
#include "auv/sim/raycast/ray_caster.h"
#include "auv/sim/sensors/sensor_cloud.h"

namespace auv::sim {

/// The scenario's `dvl_beams:` section (absent, or `enabled: false`: no beam returns are
/// published; the DVL's velocity and altitude are in `navigation:`).
struct DvlBeamsOptions {
  bool enabled = false;  ///< a section without `enabled` enables the output
  Eigen::Vector3d mount_position{0.0, 0.0, 0.2};  ///< m, transducer head on the body (FRD)
  double beam_angle = 30.0 * M_PI / 180.0;        ///< rad, each beam from the vertical (YAML _deg)
  /// rad, azimuth of the first beam from the body's x axis; the others follow 90 deg apart
  /// (YAML azimuth_offset_deg; 45: the Janus "X" layout).
  double azimuth_offset = 45.0 * M_PI / 180.0;
  double rate = 5.0;          ///< Hz, pings (as navigation.dvl_rate by default)
  double min_range = 0.3;     ///< m, along the beam
  double max_range = 60.0;    ///< m, along the beam (bottom lock range / cos(beam_angle))
  double range_noise = 0.02;  ///< m, sigma added to each return

  /// DVL head frame (axes of the body) -> body (FRD).
  Eigen::Isometry3d mounting() const;
  /// Throws ConfigError naming the field ("dvl_beams.<key>") when a value is out of range.
  void check() const;
  /// Reads the `dvl_beams:` section strictly, then check() when enabled; errors name the file
  /// and the field. `present`: the scenario has the section.
  static DvlBeamsOptions fromYaml(const YamlSection& section, bool present);
  /// The `dvl_beams:` section of a scenario file's root.
  static DvlBeamsOptions fromScenario(const YamlSection& root) {
    const YAML::Node& node = root.node();
    return fromYaml(root.child("dvl_beams"), node.IsMap() && node["dvl_beams"].IsDefined());
  }
};

class DvlBeams {
 public:
  static constexpr int kBeams = 4;

  /// Throws ConfigError when the options are invalid.
  DvlBeams(const DvlBeamsOptions& options, uint64_t seed);

  bool due(double time) const { return schedule_.due(time); }
  /// The four bottom returns at `time` from the vehicle's true pose into `world` and the
  /// seabed plane at `seabed_depth`; schedules the next ping.
  SensorCloud ping(const Eigen::Isometry3d& body_pose_true, double time, const RayCaster& world,
                   double seabed_depth);

  /// Unit beam directions in the head frame (z down), in azimuth order.
  const std::vector<Eigen::Vector3d>& beamDirections() const { return fan_.directions(); }
  const DvlBeamsOptions& options() const { return options_; }

 private:
  DvlBeamsOptions options_;
  PingSchedule schedule_;
  BeamFan fan_;
};

}  // namespace auv::sim
