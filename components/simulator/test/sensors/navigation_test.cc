// Statistical tests of the simulated navigation against analytic dead-reckoning error models.

#include "auv/sim/sensors/navigation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <vector>

#include "auv/msg/navigation.h"

namespace auv::sim {
namespace {

constexpr double kStep = 0.05;  // s, simulation step (faster than every sensor rate)

static_assert(nav_source::kDvlValid == auv::msg::ODOMETRY_SOURCE_DVL_VALID);
static_assert(nav_source::kGpsFix == auv::msg::ODOMETRY_SOURCE_GPS_FIX);
static_assert(nav_source::kPressure == auv::msg::ODOMETRY_SOURCE_PRESSURE);
static_assert(nav_source::kDeadReckoning == auv::msg::ODOMETRY_SOURCE_DEAD_RECKONING);
static_assert(nav_source::kImu == auv::msg::ODOMETRY_SOURCE_IMU);

// Every error source off: the estimate equals the truth unless a test turns one on.
NavigationOptions idealOptions() {
  NavigationOptions o;
  o.dvl_velocity_noise = 0.0;
  o.dvl_scale_error = 0.0;
  o.dvl_altitude_noise = 0.0;
  o.dvl_dropout_rate = 0.0;
  o.dvl_dropout_roughness_gain = 0.0;
  o.heading_bias = 0.0;
  o.heading_random_walk = 0.0;
  o.heading_noise = 0.0;
  o.attitude_noise = 0.0;
  o.gyro_noise = 0.0;
  o.depth_noise = 0.0;
  return o;
}

// The vehicle's truth along a run: called with the time, returns the depth and roughness.
struct Leg {
  double yaw = 0.3;        // rad, an arbitrary heading so that errors are not axis-aligned
  double surge = 1.0;      // m/s
  double altitude = 10.0;  // m
  std::function<double(double)> depth = [](double) { return 3.0; };
  std::function<double(double)> roughness = [](double) { return 0.0; };
};

using Observer = std::function<void(const VehicleState&, const NavigationSimulator&)>;

// A vehicle driven straight along legs, with its navigation simulator. The truth and the
// estimate always refer to the same instant when a leg ends.
struct Drive {
  NavigationSimulator nav;
  VehicleState truth;
  double time = 0;
  bool started = false;

  Drive(const NavigationOptions& options, uint64_t seed) : nav(options, seed) {}

  void drive(double duration, const Leg& leg, const Observer& observe = nullptr) {
    truth.yaw = leg.yaw;
    truth.surge = leg.surge;
    if (!started) {
      started = true;
      step(leg, observe);
    }
    const int steps = static_cast<int>(std::lround(duration / kStep));
    const double start = time;
    for (int i = 1; i <= steps; ++i) {
      truth.position.head<2>() += truth.velocityWorld().head<2>() * kStep;
      time = start + i * kStep;
      step(leg, observe);
    }
  }

 private:
  void step(const Leg& leg, const Observer& observe) {
    truth.position.z() = leg.depth(time);
    nav.update(truth, time, leg.altitude, leg.roughness(time));
    if (observe) observe(truth, nav);
  }
};

// Horizontal error (estimate - truth) split into along-track and cross-track (starboard) parts.
Eigen::Vector2d trackError(const NavigationSimulator& nav, const VehicleState& truth) {
  const Eigen::Vector2d error = nav.estimate().position.head<2>() - truth.position.head<2>();
  const Eigen::Vector2d along(std::cos(truth.yaw), std::sin(truth.yaw));
  const Eigen::Vector2d starboard(-std::sin(truth.yaw), std::cos(truth.yaw));
  return {error.dot(along), error.dot(starboard)};
}

double mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return s / v.size();
}
double stddev(const std::vector<double>& v) {
  const double m = mean(v);
  double s = 0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / (v.size() - 1));
}

TEST(Navigation, WhiteVelocityNoiseIsAZeroMeanRandomWalk) {
  NavigationOptions options = idealOptions();
  options.dvl_velocity_noise = 0.05;
  const int kSeeds = 50;
  std::vector<double> errors_100, errors_400;  // both horizontal axes pooled
  double reported_sigma_400 = 0;
  for (int seed = 0; seed < kSeeds; ++seed) {
    Drive run(options, seed);
    run.drive(100, Leg());
    Eigen::Vector2d e = run.nav.estimate().position.head<2>() - run.truth.position.head<2>();
    errors_100.insert(errors_100.end(), {e.x(), e.y()});
    run.drive(300, Leg());
    e = run.nav.estimate().position.head<2>() - run.truth.position.head<2>();
    errors_400.insert(errors_400.end(), {e.x(), e.y()});
    reported_sigma_400 = std::sqrt(run.nav.estimate().pose_covariance(0, 0));
  }
  // Zero-order-held white noise sigma_v for a DVL period T integrates to a random walk:
  // sigma_position(t) = sigma_v * sqrt(T * t).
  const double period = 1.0 / options.dvl_rate;
  const double expected_100 = options.dvl_velocity_noise * std::sqrt(period * 100);
  const double expected_400 = options.dvl_velocity_noise * std::sqrt(period * 400);
  const double n = errors_400.size();
  EXPECT_LT(std::abs(mean(errors_100)), 4 * expected_100 / std::sqrt(n));
  EXPECT_LT(std::abs(mean(errors_400)), 4 * expected_400 / std::sqrt(n));
  EXPECT_NEAR(stddev(errors_400), expected_400, 0.3 * expected_400);
  EXPECT_NEAR(stddev(errors_100), expected_100, 0.3 * expected_100);
  const double ratio = stddev(errors_400) / stddev(errors_100);
  EXPECT_GT(ratio, 1.6) << "spread must grow like sqrt(t): sqrt(4) = 2";
  EXPECT_LT(ratio, 2.5);
  // The filter's own covariance matches the analytic spread.
  EXPECT_NEAR(reported_sigma_400, expected_400, 0.05 * expected_400);
}

TEST(Navigation, HeadingBiasGivesCrossTrackErrorOfBiasTimesDistance) {
  NavigationOptions options;  // default noise, no scale error or dropouts
  options.dvl_scale_error = 0.0;
  options.dvl_dropout_rate = 0.0;
  options.heading_random_walk = 0.0;
  options.heading_bias = 0.02;   // rad, to starboard
  const double kDuration = 300;  // s at 1 m/s: 300 m
  std::vector<double> along, cross, reported_cross_sigma;
  for (int seed = 0; seed < 20; ++seed) {
    Drive run(options, seed);
    run.drive(kDuration, Leg());
    const Eigen::Vector2d e = trackError(run.nav, run.truth);
    along.push_back(e.x());
    cross.push_back(e.y());
    const Eigen::Vector2d starboard(-std::sin(run.truth.yaw), std::cos(run.truth.yaw));
    reported_cross_sigma.push_back(std::sqrt(
        starboard.dot(run.nav.estimate().pose_covariance.topLeftCorner<2, 2>() * starboard)));
  }
  const double distance = kDuration * 1.0;
  const double expected = options.heading_bias * distance;  // 6 m
  EXPECT_NEAR(mean(cross), expected, 0.03 * expected);
  EXPECT_NEAR(mean(along), 0.0, 0.2);  // second order: -b^2 d / 2 = -0.06 m
  // The heading-bias magnitude is in the covariance: 1 sigma cross-track ~ |b| * d.
  EXPECT_NEAR(mean(reported_cross_sigma), expected, 0.05 * expected);
}

TEST(Navigation, VelocityScaleErrorGivesAlongTrackErrorOfScaleTimesDistance) {
  NavigationOptions options;
  options.heading_bias = 0.0;
  options.heading_random_walk = 0.0;
  options.dvl_dropout_rate = 0.0;
  options.dvl_scale_error = 0.03;
  const double kDuration = 300;
  std::vector<double> along, cross;
  for (int seed = 0; seed < 20; ++seed) {
    Drive run(options, seed);
    run.drive(kDuration, Leg());
    const Eigen::Vector2d e = trackError(run.nav, run.truth);
    along.push_back(e.x());
    cross.push_back(e.y());
  }
  const double expected = options.dvl_scale_error * kDuration * 1.0;  // 9 m
  EXPECT_NEAR(mean(along), expected, 0.03 * expected);
  EXPECT_NEAR(mean(cross), 0.0, 0.15);
}

TEST(Navigation, DepthErrorStaysBoundedWhileHorizontalErrorGrows) {
  const NavigationOptions options;  // defaults, dropouts included
  Drive run(options, 3);
  Leg leg;
  leg.depth = [](double t) { return 3.0 + std::sin(t / 20.0); };
  std::vector<double> depth_errors_early, depth_errors_late;
  double max_depth_error = 0;
  run.drive(1000, leg, [&](const VehicleState& t, const NavigationSimulator& n) {
    const double e = n.estimate().position.z() - t.position.z();
    max_depth_error = std::max(max_depth_error, std::abs(e));
    (n.estimate().stamp < 200 ? depth_errors_early : depth_errors_late).push_back(e);
    EXPECT_NEAR(n.estimate().pose_covariance(2, 2), options.depth_noise * options.depth_noise,
                1e-12);
  });
  // Pressure measures depth directly: noise only, the same early and late (no drift).
  EXPECT_LT(max_depth_error, 6 * options.depth_noise);
  EXPECT_NEAR(stddev(depth_errors_early), options.depth_noise, 0.2 * options.depth_noise);
  EXPECT_NEAR(stddev(depth_errors_late), options.depth_noise, 0.2 * options.depth_noise);
  EXPECT_LT(std::abs(mean(depth_errors_late)), 0.1 * options.depth_noise);
  // Meanwhile the horizontal dead-reckoning error grew (~1 % of 1000 m).
  EXPECT_GT(trackError(run.nav, run.truth).norm(), 3.0);
}

TEST(Navigation, GpsFixAtSurfaceCollapsesErrorAndCovariance) {
  const NavigationOptions options;
  std::vector<double> errors_before, errors_after;
  for (int seed = 0; seed < 10; ++seed) {
    Drive run(options, seed);
    // A 400 m dive at 3 m (not shallow enough for GPS), then 30 s at the surface.
    run.drive(400, Leg());
    const NavigationEstimate dived = run.nav.estimate();
    errors_before.push_back(trackError(run.nav, run.truth).norm());
    EXPECT_TRUE(dived.source_flags & nav_source::kDeadReckoning);
    EXPECT_FALSE(dived.source_flags & nav_source::kGpsFix);

    Leg surface;
    surface.depth = [](double) { return 0.0; };
    run.drive(30, surface);
    const NavigationEstimate surfaced = run.nav.estimate();
    errors_after.push_back(trackError(run.nav, run.truth).norm());
    EXPECT_TRUE(surfaced.source_flags & nav_source::kGpsFix);
    EXPECT_FALSE(surfaced.source_flags & nav_source::kDeadReckoning);
    const double trace_before = dived.pose_covariance(0, 0) + dived.pose_covariance(1, 1);
    const double trace_after = surfaced.pose_covariance(0, 0) + surfaced.pose_covariance(1, 1);
    EXPECT_GT(trace_before, 2 * 2.0 * 2.0);  // > 2 m per axis after 400 m
    // ~30 fixes of sigma 1.5 m averaged: below one fix's variance, far below the dive's.
    EXPECT_LT(trace_after, 2 * options.gps_noise * options.gps_noise);
    EXPECT_LT(trace_after, trace_before / 10);

    // Back under water the fix expires and dead reckoning resumes.
    run.drive(5, Leg());
    EXPECT_TRUE(run.nav.estimate().source_flags & nav_source::kDeadReckoning);
    EXPECT_FALSE(run.nav.estimate().source_flags & nav_source::kGpsFix);
  }
  EXPECT_GT(mean(errors_before), 3.0);
  EXPECT_LT(mean(errors_after), 1.0);
}

TEST(Navigation, NoGpsBelowTheAntennaDepth) {
  NavigationOptions options = idealOptions();
  options.dvl_scale_error = 0.05;  // builds an error a fix would remove
  Drive run(options, 1);
  Leg leg;
  leg.depth = [&](double) { return options.gps_max_depth + 0.1; };
  run.drive(100, leg);
  EXPECT_FALSE(run.nav.estimate().source_flags & nav_source::kGpsFix);
  EXPECT_NEAR(trackError(run.nav, run.truth).x(), 0.05 * 100, 0.1);
}

TEST(Navigation, DropoutsAreMoreFrequentOverRoughGround) {
  NavigationOptions options;
  options.dvl_dropout_rate = 0.01;
  options.dvl_dropout_roughness_gain = 1.0;
  options.dvl_dropout_duration = 2.0;
  const double kDuration = 2000;
  auto countDropouts = [&](double roughness) {
    int onsets = 0;
    for (int seed = 0; seed < 10; ++seed) {
      Drive run(options, 100 + seed);
      Leg leg;
      leg.roughness = [roughness](double) { return roughness; };
      bool locked = true;
      run.drive(kDuration, leg, [&](const VehicleState&, const NavigationSimulator& n) {
        if (locked && !n.dvlLock()) ++onsets;
        locked = n.dvlLock();
      });
    }
    return onsets;
  };
  // Renewal process: one dropout per (mean time to dropout + mean duration); the hazard is
  // evaluated once per DVL ping and a dropout ends on a ping (about half a period later).
  auto expected = [&](double roughness) {
    const double period = 1.0 / options.dvl_rate;
    const double rate = options.dvl_dropout_rate + options.dvl_dropout_roughness_gain * roughness;
    const double p = 1 - std::exp(-rate * period);
    return 10 * kDuration / (period / p + options.dvl_dropout_duration + period / 2);
  };
  const int flat = countDropouts(0.0), rough = countDropouts(0.5);
  EXPECT_NEAR(flat, expected(0.0), 0.25 * expected(0.0));
  EXPECT_NEAR(rough, expected(0.5), 0.1 * expected(0.5));
  EXPECT_GT(rough, 10 * flat);
}

TEST(Navigation, WithoutLockVelocityDecaysAndUncertaintyGrowsFaster) {
  NavigationOptions options = idealOptions();
  options.dvl_velocity_noise = 0.02;
  options.dropout_velocity_decay = 20.0;
  options.dropout_velocity_random_walk = 0.05;
  Drive run(options, 5);
  run.drive(50, Leg());
  const double variance_50 = run.nav.estimate().pose_covariance(0, 0);
  run.drive(10, Leg());
  const double growth_locked = run.nav.estimate().pose_covariance(0, 0) - variance_50;
  const double surge_locked = run.nav.estimate().velocity.x();
  EXPECT_TRUE(run.nav.dvlLock());
  EXPECT_NEAR(run.nav.estimate().altitude, 10.0, 1e-9);

  Leg no_bottom;
  no_bottom.altitude = -1.0;  // nothing within range below
  run.drive(10, no_bottom);
  const NavigationEstimate lost = run.nav.estimate();
  EXPECT_FALSE(run.nav.dvlLock());
  EXPECT_FALSE(lost.source_flags & nav_source::kDvlValid);
  EXPECT_LT(lost.altitude, 0.0);
  // Held velocity decays with the configured time constant (10 s of 20 s: e^-0.5), within one
  // simulation step of the moment the lock was lost.
  EXPECT_NEAR(lost.velocity.x(), surge_locked * std::exp(-10.0 / 20.0), 0.01);
  EXPECT_GT(lost.pose_covariance(0, 0) - variance_50 - growth_locked, 10 * growth_locked);
  EXPECT_GT(lost.twist_covariance(0, 0), 10 * options.dvl_velocity_noise * 0.02);

  run.drive(1, Leg());
  EXPECT_TRUE(run.nav.dvlLock());
  EXPECT_TRUE(run.nav.estimate().source_flags & nav_source::kDvlValid);
}

TEST(Navigation, SameSeedGivesIdenticalOutput) {
  const NavigationOptions options;
  auto run = [&](uint64_t seed) {
    Drive run(options, seed);
    Leg leg;
    leg.roughness = [](double t) { return 0.5 + 0.5 * std::sin(t); };
    leg.depth = [](double t) { return t < 100 ? 0.0 : 3.0; };
    std::vector<double> trace;
    run.drive(200, leg, [&](const VehicleState&, const NavigationSimulator& n) {
      const NavigationEstimate& e = n.estimate();
      trace.insert(trace.end(),
                   {e.position.x(), e.position.y(), e.position.z(), e.yaw, e.velocity.x(),
                    e.altitude, e.pose_covariance(0, 5), double(e.source_flags)});
    });
    return trace;
  };
  const std::vector<double> a = run(42), b = run(42), c = run(43);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
}

TEST(Navigation, DefaultsDriftAboutOneToTwoPercentOfDistance) {
  const NavigationOptions options;
  std::vector<double> drift;
  for (int seed = 0; seed < 10; ++seed) {
    Drive run(options, seed);
    run.drive(600, Leg());
    drift.push_back(trackError(run.nav, run.truth).norm() / 600.0);
  }
  EXPECT_GT(mean(drift), 0.008);
  EXPECT_LT(mean(drift), 0.025);
}

TEST(Navigation, UpdateReportsEstimatesAtTheOutputRate) {
  NavigationSimulator nav(NavigationOptions(), 0);
  VehicleState truth;
  int due = 0;
  for (int i = 0; i < 200; ++i) due += nav.update(truth, i * 0.01, 5.0, 0.0);  // 2 s
  EXPECT_EQ(due, 20);                                                          // 10 Hz
  EXPECT_THROW(nav.update(truth, 1.0, 5.0, 0.0), std::invalid_argument);
}

TEST(NavigationOptions, ReadsYamlStrictly) {
  const YamlSection root(YAML::Load("navigation: {dvl_rate: 4, heading_bias_deg: 1.0, "
                                    "gps_noise: 2.5}"),
                         "", "test.yaml");
  const NavigationOptions o = NavigationOptions::fromYaml(root.child("navigation"));
  EXPECT_DOUBLE_EQ(o.dvl_rate, 4.0);
  EXPECT_NEAR(o.heading_bias, M_PI / 180.0, 1e-12);
  EXPECT_DOUBLE_EQ(o.gps_noise, 2.5);
  EXPECT_DOUBLE_EQ(o.depth_noise, NavigationOptions().depth_noise);  // default kept

  const YamlSection absent(YAML::Load("other: 1"), "", "test.yaml");
  EXPECT_NO_THROW(NavigationOptions::fromYaml(absent.child("navigation")));

  auto errorOf = [](const std::string& text) {
    const YamlSection r(YAML::Load(text), "", "test.yaml");
    try {
      NavigationOptions::fromYaml(r.child("navigation"));
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(errorOf("navigation: {dvl_rat: 4}").find("did you mean 'dvl_rate'"), std::string::npos);
  EXPECT_NE(errorOf("navigation: {dvl_rate: -1}").find("navigation.dvl_rate"), std::string::npos);
  EXPECT_NE(errorOf("navigation: {dvl_min_altitude: 5, dvl_max_altitude: 2}")
                .find("navigation.dvl_max_altitude"),
            std::string::npos);
  EXPECT_NE(errorOf("navigation: {gps_noise: far}").find("test.yaml"), std::string::npos);
}

TEST(NavigationOptions, CheckNamesTheField) {
  NavigationOptions o;
  o.depth_noise = -0.1;
  try {
    o.check();
    FAIL() << "negative noise accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("depth_noise"), std::string::npos);
  }
  EXPECT_THROW(NavigationSimulator(o, 0), ConfigError);
}

}  // namespace
}  // namespace auv::sim
