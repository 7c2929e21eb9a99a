#pragma once
// A mechanically scanned pencil-beam profiling sonar (Tritech Micron / Imagenex 881 class, as
// on Sparus II, paper section 4.1) scanning the vehicle's horizontal plane. Each ping casts a
// small grid of rays over the beam's -3 dB cone into the *true* world (the sonar sees the real
// rocks; the map is built with the drifting navigation, which is the point of the simulation),
// forms the echo envelope from incidence angle and beam pattern, detects the first return above
// a threshold, adds range noise and occasional false returns, and steps the head.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <random>
#include <vector>

#include "auv/sim/common/yaml_section.h"
#include "auv/sim/raycast/ray_caster.h"

namespace auv::sim {

/// Bits of SonarPing::flags; same values as SONAR_BEAM_* in idl/msg/sensors.idl.
namespace sonar_flags {
constexpr uint32_t kEchoReturned = 0x01;  ///< an echo within [min_range, max_range]
constexpr uint32_t kSaturated = 0x02;     ///< some bin clipped at 255
constexpr uint32_t kScanStart = 0x04;     ///< first ping of a new sweep (head wrapped/reversed)
}  // namespace sonar_flags

/// The scenario's `sonar:` section. Angles are radians here; YAML gives them in degrees under
/// `<name>_deg` keys. Defaults: a Tritech Micron (3 deg x 35 deg fan beam, 20 m, 1.8 deg step).
struct SonarOptions {
  /// m, head position on the body (FRD): on top of Sparus II's front payload.
  Eigen::Vector3d mount_position{0.55, 0.0, -0.15};
  double mount_yaw = 0.0;  ///< rad, body-frame yaw of the head's zero angle (YAML yaw_deg)

  double max_range = 20.0;                 ///< m
  double min_range = 0.3;                  ///< m, blanking: nothing closer is seen
  double step_angle = 1.8 * M_PI / 180.0;  ///< rad, head step between pings (YAML step_deg)
  /// true: the head turns continuously through 360 deg; false: it sweeps back and forth over
  /// [sector_left, sector_right]. YAML: giving `sector_deg: [left, right]` selects the sector.
  bool continuous = true;
  double sector_left = -M_PI / 2;  ///< rad, head angle of the left limit (negative = port)
  double sector_right = M_PI / 2;  ///< rad, head angle of the right limit
  /// Hz; 0 = automatic: one two-way travel time at max_range plus 13 ms for the head step and
  /// processing (25 Hz at 20 m). Must not exceed sound_speed / (2 max_range).
  double ping_rate = 0.0;

  double horizontal_beam_width = 3.0 * M_PI / 180.0;  ///< rad, -3 dB, in the scan plane
  double vertical_beam_width = 35.0 * M_PI / 180.0;   ///< rad, -3 dB, across the scan plane
  int rays_horizontal = 3;  ///< rays across the beam in the scan plane (cell centres of a grid)
  int rays_vertical = 7;    ///< rays across the beam vertically

  double range_noise = 0.05;               ///< m, sigma added to a detected range
  double false_return_probability = 0.01;  ///< per ping, a spurious echo at a random range
  int bins = 200;                          ///< intensity bins over [min_range, max_range]
  double detection_threshold = 40.0;       ///< bin units (0..255), first crossing = the return
  double gain = 4.0;  ///< a perpendicular target filling the beam gives 255 * gain (clipped);
                      ///< time-varying gain is assumed to cancel spreading loss
  double noise_level = 4.0;     ///< bin units, sigma of the receiver noise (|gaussian|)
  double pulse_length = 0.1;    ///< m, range extent of one echo (c * pulse duration / 2)
  double sound_speed = 1500.0;  ///< m/s

  /// The ping rate in use (resolves ping_rate = 0).
  double effectivePingRate() const;
  /// m, width of one intensity bin.
  double rangeResolution() const { return (max_range - min_range) / bins; }
  /// Sonar head frame -> body (FRD): z is the rotation axis (down), x the head's zero.
  Eigen::Isometry3d mounting() const;

  /// Throws ConfigError naming the field when a value is out of range.
  void check() const;
  /// Reads the `sonar:` section strictly (unknown keys are errors), then check().
  static SonarOptions fromYaml(const YamlSection& section);
};

/// One ping, as published on `sonar/beam`.
struct SonarPing {
  double stamp = 0.0;  ///< s
  double angle = 0.0;  ///< rad, head angle about the sonar z axis, 0 = sonar x, in (-pi, pi]
  double horizontal_beam_width = 0.0;       ///< rad
  double vertical_beam_width = 0.0;         ///< rad
  double min_range = 0.0, max_range = 0.0;  ///< m
  double range_resolution = 0.0;            ///< m, width of one bin
  double sound_speed = 0.0;                 ///< m/s
  std::vector<float> ranges;                ///< m, the first return; empty when no echo
  std::vector<float> intensities;           ///< 0..1, strength of each return
  std::vector<uint8_t> bins;                ///< bins[i] covers min_range + i * range_resolution
  uint32_t flags = 0;                       ///< sonar_flags::k*
  Eigen::Isometry3d mounting = Eigen::Isometry3d::Identity();  ///< sonar head -> body

  bool echo() const { return (flags & sonar_flags::kEchoReturned) != 0; }
  /// Unit beam axis in the sonar frame.
  Eigen::Vector3d direction() const;
  /// The point at `range` along the beam axis, in the body frame.
  Eigen::Vector3d pointInBody(double range) const;
};

class ProfilingSonar {
 public:
  /// Throws ConfigError when the options are invalid.
  ProfilingSonar(const SonarOptions& options, uint64_t seed);

  /// True when a ping is due at `time` (s); the first call is always due.
  bool due(double time) const { return time + 1e-9 >= next_ping_time_; }
  /// s, when the next ping is scheduled.
  double nextPingTime() const { return next_ping_time_; }
  /// Pings at `time` from the vehicle's true pose (body FRD -> world NED) into `world`, then
  /// steps the head and schedules the next ping.
  SonarPing ping(const Eigen::Isometry3d& body_pose_true, double time, const RayCaster& world);

  /// rad, head angle the next ping will use, in (-pi, pi].
  double headAngle() const;
  const SonarOptions& options() const { return options_; }

 private:
  void advanceHead();
  double gaussian(double sigma) { return sigma * normal_(rng_); }

  SonarOptions options_;
  double period_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};

  // Beam pattern: ray directions in the head frame at angle 0 and their two-way weights.
  std::vector<Eigen::Vector3d> ray_directions_;
  std::vector<double> ray_weights_;  ///< normalised to sum 1

  double next_ping_time_ = -1e300;
  bool first_ping_ = true;
  // Continuous: the head angle is step_count_ * step_angle (exact revolutions, no drift).
  int64_t step_count_ = 0;
  // Sector: the head angle and direction of travel (+1 towards sector_right).
  double sector_angle_ = 0.0;
  int direction_ = 1;
  bool reversed_ = false;  ///< the head turned around at a limit before the next ping

  // Scratch buffers reused across pings.
  std::vector<Eigen::Vector3f> origins_, directions_;
  std::vector<RayHit> hits_;
  std::vector<double> envelope_;
};

}  // namespace auv::sim
