#include "auv/sim/sensors/navigation.h"

#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace auv::sim {
namespace {

void require(bool ok, const char* field, const char* what, double value) {
  requireOption(ok, std::string("navigation.") + field, what, value);
}

bool positive(double x) { return std::isfinite(x) && x > 0.0; }
bool nonNegative(double x) { return std::isfinite(x) && x >= 0.0; }

}  // namespace

void NavigationOptions::check() const {
  require(positive(output_rate), "output_rate", "a rate > 0 Hz", output_rate);
  require(positive(dvl_rate), "dvl_rate", "a rate > 0 Hz", dvl_rate);
  require(nonNegative(dvl_velocity_noise), "dvl_velocity_noise", "a sigma >= 0 m/s",
          dvl_velocity_noise);
  require(std::isfinite(dvl_scale_error) && std::abs(dvl_scale_error) < 0.5, "dvl_scale_error",
          "a fraction in (-0.5, 0.5)", dvl_scale_error);
  require(nonNegative(dvl_min_altitude), "dvl_min_altitude", "an altitude >= 0 m",
          dvl_min_altitude);
  require(positive(dvl_max_altitude) && dvl_max_altitude > dvl_min_altitude, "dvl_max_altitude",
          "an altitude > dvl_min_altitude", dvl_max_altitude);
  require(nonNegative(dvl_altitude_noise), "dvl_altitude_noise", "a sigma >= 0 m",
          dvl_altitude_noise);
  require(nonNegative(dvl_dropout_rate), "dvl_dropout_rate", "a rate >= 0 1/s", dvl_dropout_rate);
  require(nonNegative(dvl_dropout_roughness_gain), "dvl_dropout_roughness_gain", "a gain >= 0",
          dvl_dropout_roughness_gain);
  require(positive(dvl_dropout_duration), "dvl_dropout_duration", "a duration > 0 s",
          dvl_dropout_duration);
  require(nonNegative(dropout_velocity_decay), "dropout_velocity_decay",
          "a time constant >= 0 s (0 = hold)", dropout_velocity_decay);
  require(nonNegative(dropout_velocity_random_walk), "dropout_velocity_random_walk",
          "a value >= 0 m/s/sqrt(s)", dropout_velocity_random_walk);
  require(positive(ahrs_rate), "ahrs_rate", "a rate > 0 Hz", ahrs_rate);
  require(std::isfinite(heading_bias) && std::abs(heading_bias) <= 0.5, "heading_bias",
          "a bias within +-0.5 rad (+-28.6 deg)", heading_bias);
  require(nonNegative(heading_random_walk), "heading_random_walk", "a value >= 0 rad/sqrt(s)",
          heading_random_walk);
  require(nonNegative(heading_noise), "heading_noise", "a sigma >= 0 rad", heading_noise);
  require(nonNegative(attitude_noise), "attitude_noise", "a sigma >= 0 rad", attitude_noise);
  require(nonNegative(gyro_noise), "gyro_noise", "a sigma >= 0 rad/s", gyro_noise);
  require(nonNegative(depth_noise), "depth_noise", "a sigma >= 0 m", depth_noise);
  require(positive(gps_rate), "gps_rate", "a rate > 0 Hz", gps_rate);
  require(nonNegative(gps_noise), "gps_noise", "a sigma >= 0 m", gps_noise);
  require(nonNegative(gps_max_depth), "gps_max_depth", "a depth >= 0 m", gps_max_depth);
  require(nonNegative(initial_position_noise), "initial_position_noise", "a sigma >= 0 m",
          initial_position_noise);
}

NavigationOptions NavigationOptions::fromYaml(const YamlSection& section) {
  section.rejectUnknownKeys({"output_rate",
                             "dvl_rate",
                             "dvl_velocity_noise",
                             "dvl_scale_error",
                             "dvl_min_altitude",
                             "dvl_max_altitude",
                             "dvl_altitude_noise",
                             "dvl_dropout_rate",
                             "dvl_dropout_roughness_gain",
                             "dvl_dropout_duration",
                             "dropout_velocity_decay",
                             "dropout_velocity_random_walk",
                             "ahrs_rate",
                             "heading_bias_deg",
                             "heading_random_walk_deg",
                             "heading_noise_deg",
                             "attitude_noise_deg",
                             "gyro_noise",
                             "depth_noise",
                             "gps_rate",
                             "gps_noise",
                             "gps_max_depth",
                             "initial_position_noise"});
  NavigationOptions o;
  section.read("output_rate", o.output_rate, 1e-3);
  section.read("dvl_rate", o.dvl_rate, 1e-3);
  section.read("dvl_velocity_noise", o.dvl_velocity_noise, 0.0);
  section.read("dvl_scale_error", o.dvl_scale_error, -0.49, 0.49);
  section.read("dvl_min_altitude", o.dvl_min_altitude, 0.0);
  section.read("dvl_max_altitude", o.dvl_max_altitude, 0.0);
  section.read("dvl_altitude_noise", o.dvl_altitude_noise, 0.0);
  section.read("dvl_dropout_rate", o.dvl_dropout_rate, 0.0);
  section.read("dvl_dropout_roughness_gain", o.dvl_dropout_roughness_gain, 0.0);
  section.read("dvl_dropout_duration", o.dvl_dropout_duration, 1e-3);
  section.read("dropout_velocity_decay", o.dropout_velocity_decay, 0.0);
  section.read("dropout_velocity_random_walk", o.dropout_velocity_random_walk, 0.0);
  section.read("ahrs_rate", o.ahrs_rate, 1e-3);
  section.readDegrees("heading_bias_deg", o.heading_bias, -28.6, 28.6);
  section.readDegrees("heading_random_walk_deg", o.heading_random_walk, 0.0);
  section.readDegrees("heading_noise_deg", o.heading_noise, 0.0);
  section.readDegrees("attitude_noise_deg", o.attitude_noise, 0.0);
  section.read("gyro_noise", o.gyro_noise, 0.0);
  section.read("depth_noise", o.depth_noise, 0.0);
  section.read("gps_rate", o.gps_rate, 1e-3);
  section.read("gps_noise", o.gps_noise, 0.0);
  section.read("gps_max_depth", o.gps_max_depth, 0.0);
  section.read("initial_position_noise", o.initial_position_noise, 0.0);
  checkInFile(section, o);
  return o;
}

Eigen::Isometry3d NavigationEstimate::pose() const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = position;
  return T;
}

NavigationSimulator::NavigationSimulator(const NavigationOptions& options, uint64_t seed)
    : options_(options), rng_(seed) {
  options_.check();
}

bool NavigationSimulator::due(double time, double rate, double& next_time) {
  if (time + 1e-9 < next_time) return false;
  next_time += 1.0 / rate;
  // A caller stepping slower than the sensor gets one sample per step, not a burst.
  if (next_time <= time) next_time = time + 1.0 / rate;
  return true;
}

bool NavigationSimulator::update(const VehicleState& truth, double time, double true_altitude,
                                 double terrain_roughness) {
  if (!std::isfinite(time)) throw std::invalid_argument("NavigationSimulator: time is not finite");
  if (!initialized_) {
    initialize(truth, time);
  } else {
    if (time < last_time_) {
      throw std::invalid_argument("NavigationSimulator: time went backwards (" +
                                  std::to_string(time) + " < " + std::to_string(last_time_) + ")");
    }
    propagate(time - last_time_);
  }
  last_time_ = time;

  if (due(time, options_.dvl_rate, next_dvl_)) {
    sampleDvl(truth, time, true_altitude, terrain_roughness);
  }
  if (due(time, options_.ahrs_rate, next_ahrs_)) sampleAhrsAndPressure(truth, time);
  if (truth.position.z() <= options_.gps_max_depth && due(time, options_.gps_rate, next_gps_)) {
    sampleGps(truth, time);
  }
  fillEstimate(time);
  return due(time, options_.output_rate, next_output_);
}

void NavigationSimulator::initialize(const VehicleState& truth, double time) {
  initialized_ = true;
  next_dvl_ = next_ahrs_ = next_gps_ = next_output_ = time;
  last_ahrs_time_ = time;
  lock_lost_time_ = time;
  const double sigma0 = options_.initial_position_noise;
  position_ = truth.position;
  position_.x() += gaussian(sigma0);
  position_.y() += gaussian(sigma0);
  yaw_ = truth.yaw;

  covariance_.setZero();
  covariance_(kX, kX) = covariance_(kY, kY) = sigma0 * sigma0;
  covariance_(kZ, kZ) = options_.depth_noise * options_.depth_noise;
  // The filter knows the AHRS and DVL specifications (bias and scale magnitudes), not their
  // actual sign: they enter as 1-sigma uncertainties of the consider states.
  covariance_(kHeading, kHeading) = options_.heading_bias * options_.heading_bias;
  covariance_(kScale, kScale) = options_.dvl_scale_error * options_.dvl_scale_error;
  // The velocity is unknown (0 +- 1 m/s) until the first DVL lock.
  covariance_(kSurge, kSurge) = covariance_(kSway, kSway) = 1.0;
}

void NavigationSimulator::propagate(double dt) {
  if (dt <= 0.0) return;
  const double c = std::cos(yaw_), s = std::sin(yaw_);
  Eigen::Matrix2d rotation;
  rotation << c, -s, s, c;
  Eigen::Matrix2d rotation_derivative;  // d rotation / d yaw
  rotation_derivative << -s, -c, c, -s;
  const Eigen::Vector2d body_velocity = velocity_.head<2>();

  // Dead reckoning: the held DVL velocity rotated by the AHRS heading (zero-order hold).
  position_.head<2>() += rotation * body_velocity * dt;

  // Error-state propagation: d(position error)/dt = R (s v + dv) + R' v (heading error).
  StateMatrix F = StateMatrix::Identity();
  const Eigen::Vector2d heading_sensitivity = rotation_derivative * body_velocity;
  F.block<2, 1>(kX, kHeading) = heading_sensitivity * dt;
  if (dvl_lock_) F.block<2, 1>(kX, kScale) = rotation * body_velocity * dt;
  F.block<2, 2>(kX, kSurge) = rotation * dt;
  // Without lock the filter treats the velocity as a first-order Gauss-Markov process: the
  // held estimate decays by `decay` and its error forgets the last measurement.
  const double decay = (!dvl_lock_ && options_.dropout_velocity_decay > 0.0)
                           ? std::exp(-dt / options_.dropout_velocity_decay)
                           : 1.0;
  F(kSurge, kSurge) = F(kSway, kSway) = decay;
  covariance_ = F * covariance_ * F.transpose();

  covariance_(kHeading, kHeading) +=
      options_.heading_random_walk * options_.heading_random_walk * dt;
  // White heading noise held for one AHRS period acts on position like a random walk.
  covariance_.block<2, 2>(kX, kX) += heading_sensitivity * heading_sensitivity.transpose() *
                                     options_.heading_noise * options_.heading_noise /
                                     options_.ahrs_rate * dt;
  if (!dvl_lock_) {
    // The held velocity goes stale: it decays towards 0 while its variance relaxes towards the
    // velocity at lock loss squared (the decay's own error) plus a random walk.
    velocity_ *= decay;
    const double q = options_.dropout_velocity_random_walk;
    const double forget = 1.0 - decay * decay;
    covariance_(kSurge, kSurge) +=
        forget * velocity_at_loss_.x() * velocity_at_loss_.x() + q * q * dt;
    covariance_(kSway, kSway) +=
        forget * velocity_at_loss_.y() * velocity_at_loss_.y() + q * q * dt;
  }
}

void NavigationSimulator::sampleDvl(const VehicleState& truth, double time, double true_altitude,
                                    double terrain_roughness) {
  // Dropouts: a Poisson process whose rate grows with the roughness of the ground below
  // (over rocks the beams see different ranges and the DVL loses or corrupts its lock).
  const double period = 1.0 / options_.dvl_rate;
  const double draw = uniform_(rng_);
  if (in_dropout_) {
    if (time + 1e-9 >= dropout_end_) in_dropout_ = false;
  } else {
    const double rate = options_.dvl_dropout_rate +
                        options_.dvl_dropout_roughness_gain * std::max(0.0, terrain_roughness);
    if (draw < 1.0 - std::exp(-rate * period)) {
      in_dropout_ = true;
      dropout_end_ =
          time + std::exponential_distribution<double>(1.0 / options_.dvl_dropout_duration)(rng_);
    }
  }
  const bool in_range =
      true_altitude >= options_.dvl_min_altitude && true_altitude <= options_.dvl_max_altitude;
  const bool was_locked = dvl_lock_;
  dvl_lock_ = in_range && !in_dropout_;

  // Draw the noise every ping so the random sequence does not depend on the lock history.
  const double sigma = options_.dvl_velocity_noise;
  const Eigen::Vector3d noise(gaussian(sigma), gaussian(sigma), gaussian(sigma));
  const double altitude_noise = gaussian(options_.dvl_altitude_noise);
  if (!dvl_lock_) {
    altitude_ = -1.0;
    if (was_locked) {
      lock_lost_time_ = time;
      velocity_at_loss_ = velocity_;
    }
    return;
  }
  const Eigen::Vector3d true_velocity(truth.surge, truth.sway, truth.heave);
  velocity_ = (1.0 + options_.dvl_scale_error) * true_velocity + noise;
  altitude_ = std::max(0.0, true_altitude + altitude_noise);
  // A fresh measurement: its noise is independent of everything before.
  for (int i : {int(kSurge), int(kSway)}) {
    covariance_.row(i).setZero();
    covariance_.col(i).setZero();
    covariance_(i, i) = sigma * sigma;
  }
}

void NavigationSimulator::sampleAhrsAndPressure(const VehicleState& truth, double time) {
  const double dt = time - last_ahrs_time_;
  last_ahrs_time_ = time;
  heading_drift_ += gaussian(options_.heading_random_walk * std::sqrt(std::max(0.0, dt)));
  yaw_ = wrapAngle(truth.yaw + options_.heading_bias + heading_drift_ +
                   gaussian(options_.heading_noise));
  // Sparus II is passively stable: true roll and pitch are 0, the AHRS reports noise.
  roll_ = gaussian(options_.attitude_noise);
  pitch_ = gaussian(options_.attitude_noise);
  yaw_rate_ = truth.yaw_rate + gaussian(options_.gyro_noise);

  // Depth is measured directly: its error is the sensor noise and never accumulates.
  position_.z() = truth.position.z() + gaussian(options_.depth_noise);
  covariance_.row(kZ).setZero();
  covariance_.col(kZ).setZero();
  covariance_(kZ, kZ) = options_.depth_noise * options_.depth_noise;
}

void NavigationSimulator::sampleGps(const VehicleState& truth, double time) {
  const double sigma = options_.gps_noise;
  const Eigen::Vector2d fix(truth.position.x() + gaussian(sigma),
                            truth.position.y() + gaussian(sigma));
  Eigen::Matrix<double, 2, kStates> H = Eigen::Matrix<double, 2, kStates>::Zero();
  H(0, kX) = H(1, kY) = 1.0;
  const Eigen::Matrix2d R = Eigen::Matrix2d::Identity() * std::max(sigma * sigma, 1e-12);
  const Eigen::Matrix2d S = H * covariance_ * H.transpose() + R;
  Eigen::Matrix<double, kStates, 2> K = covariance_ * H.transpose() * S.inverse();
  // Schmidt-Kalman: only x, y are corrected; heading, scale, velocity and depth errors are
  // "consider" states the filter cannot estimate from a fix, so their gain rows are zero.
  K.bottomRows<kStates - 2>().setZero();
  position_.head<2>() += K.topRows<2>() * (fix - position_.head<2>());
  const StateMatrix I_KH = StateMatrix::Identity() - K * H;
  covariance_ = I_KH * covariance_ * I_KH.transpose() + K * R * K.transpose();  // Joseph form
  last_gps_fix_time_ = time;
}

void NavigationSimulator::fillEstimate(double time) {
  NavigationEstimate& e = estimate_;
  e.stamp = time;
  e.position = position_;
  e.roll = roll_;
  e.pitch = pitch_;
  e.yaw = yaw_;
  e.velocity = velocity_;
  e.angular_velocity = Eigen::Vector3d(0.0, 0.0, yaw_rate_);
  e.altitude = altitude_;

  const double attitude_var = options_.attitude_noise * options_.attitude_noise;
  e.pose_covariance.setZero();
  e.pose_covariance.topLeftCorner<3, 3>() = covariance_.topLeftCorner<3, 3>();
  e.pose_covariance(3, 3) = e.pose_covariance(4, 4) = attitude_var;
  e.pose_covariance(5, 5) =
      covariance_(kHeading, kHeading) + options_.heading_noise * options_.heading_noise;
  e.pose_covariance.block<3, 1>(0, 5) = covariance_.block<3, 1>(kX, kHeading);
  e.pose_covariance.block<1, 3>(5, 0) = covariance_.block<1, 3>(kHeading, kX);

  const double velocity_var = options_.dvl_velocity_noise * options_.dvl_velocity_noise;
  const double gyro_var = options_.gyro_noise * options_.gyro_noise;
  e.twist_covariance.setZero();
  e.twist_covariance.topLeftCorner<2, 2>() = covariance_.block<2, 2>(kSurge, kSurge);
  if (dvl_lock_) {
    const Eigen::Vector2d v = velocity_.head<2>();
    e.twist_covariance.topLeftCorner<2, 2>() += covariance_(kScale, kScale) * v * v.transpose();
    e.twist_covariance(2, 2) = velocity_var;
  } else {
    // Heave is not in the error state: the same Gauss-Markov model in closed form.
    const double q = options_.dropout_velocity_random_walk;
    const double elapsed = time - lock_lost_time_;
    const double decay = options_.dropout_velocity_decay > 0.0
                             ? std::exp(-2.0 * elapsed / options_.dropout_velocity_decay)
                             : 1.0;
    e.twist_covariance(2, 2) = velocity_var * decay +
                               (1.0 - decay) * velocity_at_loss_.z() * velocity_at_loss_.z() +
                               q * q * elapsed;
  }
  e.twist_covariance(3, 3) = e.twist_covariance(4, 4) = e.twist_covariance(5, 5) = gyro_var;

  uint32_t flags = nav_source::kImu | nav_source::kPressure;
  if (dvl_lock_) flags |= nav_source::kDvlValid;
  // A fix counts as current while the next one is expected (1.5 GPS periods).
  if (time - last_gps_fix_time_ <= 1.5 / options_.gps_rate + 1e-9) {
    flags |= nav_source::kGpsFix;
  } else {
    flags |= nav_source::kDeadReckoning;
  }
  e.source_flags = flags;
}

}  // namespace auv::sim
