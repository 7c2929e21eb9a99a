#pragma once
// Simulated navigation of a Sparus II-like AUV: DVL, AHRS (IMU), pressure sensor and GPS, fused
// by dead reckoning as the vehicle's own navigation filter does (COLA2 navigator: velocity from
// the DVL rotated by the AHRS heading and integrated, depth from pressure, GPS fixes at the
// surface). The sensors carry noise, biases and dropouts so that the estimate drifts away from
// the truth like in the paper's field trial (section 4.2: "accumulation of errors in the dead
// reckoning system ... the DVL may provide incorrect data when navigating over rocks").

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <random>

#include "auv/sim/common/yaml_section.h"
#include "auv/sim/vehicle/vehicle.h"

namespace auv::sim {

/// Bits of NavigationEstimate::source_flags; same values as ODOMETRY_SOURCE_* in
/// idl/msg/navigation.idl so the simulator component can copy them into the message.
namespace nav_source {
constexpr uint32_t kDvlValid = 0x01;       ///< DVL bottom lock, velocity aided
constexpr uint32_t kGpsFix = 0x02;         ///< GPS fix used recently (at the surface)
constexpr uint32_t kPressure = 0x04;       ///< depth from the pressure sensor
constexpr uint32_t kDeadReckoning = 0x08;  ///< position integrated without absolute fix
constexpr uint32_t kImu = 0x10;            ///< attitude/heading from the AHRS
}  // namespace nav_source

/// Sensor and filter settings: the scenario's `navigation:` section. Angles are radians here;
/// in YAML they are given in degrees under `<name>_deg` keys (like the scenario's `yaw_deg`).
/// Defaults: a low-cost suite whose horizontal error grows ~1-2 % of the distance travelled
/// (0.5 deg heading bias -> 0.9 % cross-track, +1 % DVL scale -> 1 % along-track).
struct NavigationOptions {
  double output_rate = 10.0;  ///< Hz, rate at which update() reports a new estimate

  // DVL (bottom tracking).
  double dvl_rate = 5.0;             ///< Hz, velocity measurements
  double dvl_velocity_noise = 0.02;  ///< m/s, white noise sigma per body axis
  double dvl_scale_error = 0.01;     ///< fraction, measured = (1 + this) * true (+0.01 = +1 %)
  double dvl_min_altitude = 0.3;     ///< m, no bottom lock closer than this
  double dvl_max_altitude = 50.0;    ///< m, no bottom lock farther than this
  double dvl_altitude_noise = 0.05;  ///< m, sigma of the measured altitude
  double dvl_dropout_rate = 0.005;   ///< 1/s, chance per second of losing lock over flat ground
  double dvl_dropout_roughness_gain = 0.5;     ///< 1/s per unit of roughness (e.g. |d altitude/dt|
                                               ///< in m/s): dropouts are likelier over rocks
  double dvl_dropout_duration = 2.0;           ///< s, mean (exponential) length of one dropout
  double dropout_velocity_decay = 20.0;        ///< s, time constant with which the held velocity
                                               ///< decays towards 0 without lock (the filter's
                                               ///< Gauss-Markov velocity model); 0 = hold it
  double dropout_velocity_random_walk = 0.05;  ///< m/s/sqrt(s), growth of the velocity
                                               ///< uncertainty without lock

  // AHRS (heading, roll, pitch, yaw rate) and pressure sensor, sampled together.
  double ahrs_rate = 20.0;              ///< Hz
  double heading_bias = 0.0087;         ///< rad, constant heading error (YAML heading_bias_deg)
  double heading_random_walk = 1.7e-4;  ///< rad/sqrt(s), drift of the heading error
                                        ///< (YAML heading_random_walk_deg, deg/sqrt(s))
  double heading_noise = 0.0035;        ///< rad, white heading noise sigma (YAML heading_noise_deg)
  double attitude_noise = 0.0017;       ///< rad, roll/pitch noise sigma (YAML attitude_noise_deg)
  double gyro_noise = 0.002;            ///< rad/s, yaw-rate noise sigma
  double depth_noise = 0.02;            ///< m, pressure-depth noise sigma

  // GPS (only at the surface).
  double gps_rate = 1.0;       ///< Hz
  double gps_noise = 1.5;      ///< m, horizontal sigma per axis
  double gps_max_depth = 0.3;  ///< m, the antenna is out of the water above this depth

  double initial_position_noise = 0.0;  ///< m, sigma of the initial horizontal position error

  /// Throws ConfigError naming the field when a value is out of range.
  void check() const;
  /// Reads the `navigation:` section strictly (unknown keys are errors), then check().
  static NavigationOptions fromYaml(const YamlSection& section);
};

/// The navigation filter's output, as published on `nav/odometry`.
struct NavigationEstimate {
  double stamp = 0.0;                         ///< s, time of the estimate
  Eigen::Vector3d position{0, 0, 0};          ///< m NED (z = depth)
  double roll = 0.0, pitch = 0.0;             ///< rad, from the AHRS
  double yaw = 0.0;                           ///< rad, in (-pi, pi], 0 = north
  Eigen::Vector3d velocity{0, 0, 0};          ///< m/s, body FRD (surge, sway, heave)
  Eigen::Vector3d angular_velocity{0, 0, 0};  ///< rad/s, body (p, q, r)
  double altitude = -1.0;  ///< m, DVL-measured distance to the seabed; < 0 without lock
  /// Order (x, y, z, roll, pitch, yaw); m^2, rad^2. Grows while dead reckoning, GPS resets it.
  Eigen::Matrix<double, 6, 6> pose_covariance = Eigen::Matrix<double, 6, 6>::Zero();
  /// Order (u, v, w, p, q, r); (m/s)^2, (rad/s)^2.
  Eigen::Matrix<double, 6, 6> twist_covariance = Eigen::Matrix<double, 6, 6>::Zero();
  uint32_t source_flags = 0;  ///< nav_source::k* bits

  double yawRate() const { return angular_velocity.z(); }
  /// Estimated body FRD -> world NED.
  Eigen::Isometry3d pose() const;
};

/// Simulates the sensors from the true vehicle state and runs the dead-reckoning filter.
/// Deterministic for a given seed and sequence of update() calls.
///
/// Filter: position integrates R(yaw_ahrs) * v_dvl (zero-order hold between samples); depth is
/// the pressure reading; GPS fixes update x, y with a Kalman gain. The covariance is that of an
/// error state (x, y, z, heading error, DVL scale error, surge and sway velocity errors) in
/// which heading and scale are "consider" states (Schmidt-Kalman: GPS does not estimate them,
/// since the filter has no way to correct them), so the reported covariance stays consistent
/// with the actual error statistics.
class NavigationSimulator {
 public:
  NavigationSimulator(const NavigationOptions& options, uint64_t seed);

  /// Advances sensors and filter to `time` (s, non-decreasing; call at the simulation rate,
  /// faster than the sensor rates). `true_altitude`: m from the DVL to the seabed, < 0 when
  /// nothing is below within range. `terrain_roughness`: >= 0, e.g. |d altitude / dt| in m/s;
  /// raises the dropout rate. Returns true when a new estimate is due (output_rate).
  bool update(const VehicleState& truth, double time, double true_altitude,
              double terrain_roughness);

  /// The latest estimate (valid after the first update()).
  const NavigationEstimate& estimate() const { return estimate_; }
  /// True while the DVL has bottom lock (in range and not in a dropout).
  bool dvlLock() const { return dvl_lock_; }
  /// True while a random dropout is under way (lock lost even if the seabed is in range).
  bool inDropout() const { return in_dropout_; }
  const NavigationOptions& options() const { return options_; }

 private:
  // Indices of the error state.
  enum : int { kX = 0, kY, kZ, kHeading, kScale, kSurge, kSway, kStates };
  using StateMatrix = Eigen::Matrix<double, kStates, kStates>;

  void initialize(const VehicleState& truth, double time);
  void propagate(double dt);
  void sampleDvl(const VehicleState& truth, double time, double true_altitude,
                 double terrain_roughness);
  void sampleAhrsAndPressure(const VehicleState& truth, double time);
  void sampleGps(const VehicleState& truth, double time);
  void fillEstimate(double time);
  /// True (and schedules the next sample) when a sensor with this rate is due at `time`.
  static bool due(double time, double rate, double& next_time);
  double gaussian(double sigma) { return sigma * normal_(rng_); }

  NavigationOptions options_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};

  bool initialized_ = false;
  double last_time_ = 0.0;
  double next_dvl_ = 0.0, next_ahrs_ = 0.0, next_gps_ = 0.0, next_output_ = 0.0;
  double last_ahrs_time_ = 0.0;
  double last_gps_fix_time_ = -1e300;

  // Sensor state (what the instruments currently report).
  bool dvl_lock_ = false;
  bool in_dropout_ = false;
  double dropout_end_ = 0.0;
  double lock_lost_time_ = 0.0;
  Eigen::Vector3d velocity_at_loss_{0, 0, 0};  ///< m/s body, held estimate when lock was lost
  double heading_drift_ = 0.0;                 ///< rad, random-walk part of the AHRS heading error

  // Filter state.
  Eigen::Vector3d velocity_{0, 0, 0};  ///< m/s body, held between DVL samples
  Eigen::Vector3d position_{0, 0, 0};  ///< m NED
  double yaw_ = 0.0, roll_ = 0.0, pitch_ = 0.0, yaw_rate_ = 0.0;
  double altitude_ = -1.0;
  StateMatrix covariance_ = StateMatrix::Zero();

  NavigationEstimate estimate_;
};

}  // namespace auv::sim
