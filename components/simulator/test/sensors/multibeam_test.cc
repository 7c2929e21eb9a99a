// Tests of the forward-looking multibeam and the DVL beams: fan geometry against the options,
// returns against analytic meshes and the flat seabed, and validation naming the field.

#include "auv/sim/sensors/multibeam.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "../core/test_meshes.h"
#include "auv/sim/sensors/dvl_beams.h"
#include "auv/sim/vehicle/vehicle.h"

namespace auv::sim {
namespace {

constexpr double kDeg = M_PI / 180.0;

struct World {
  explicit World(Mesh m) : mesh(std::move(m)), caster(mesh) {}
  Mesh mesh;
  RayCaster caster;
};

// A world whose mesh is far away from everything the tests look at: only the seabed plane.
World emptyWorld() { return World(test::box({1000, 1000, 0}, {1001, 1001, 1})); }

Eigen::Isometry3d vehiclePose(const Eigen::Vector3d& position, double yaw) {
  VehicleState state;
  state.position = position;
  state.yaw = yaw;
  return state.pose();
}

MultibeamOptions quietFan() {
  MultibeamOptions o;
  o.enabled = true;
  o.range_noise = 0.0;
  return o;
}

YamlSection scenarioText(const std::string& text) {
  return config::loadYamlText(text, "scenario.yaml");
}

std::string errorOf(const std::string& text) {
  try {
    MultibeamOptions::fromScenario(scenarioText(text));
    DvlBeamsOptions::fromScenario(scenarioText(text));
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(MultibeamTest, FanDirectionsFollowTheOptions) {
  MultibeamOptions o = quietFan();
  o.beams = 5;
  o.rows = 3;
  o.horizontal_aperture = 120 * kDeg;
  o.vertical_aperture = 20 * kDeg;
  const Multibeam sonar(o, 1);
  const auto& d = sonar.beamDirections();
  ASSERT_EQ(d.size(), 15u);
  for (const Eigen::Vector3d& v : d) EXPECT_NEAR(v.norm(), 1.0, 1e-12);
  // Row 1 is the fan's axis plane: azimuths -60, -30, 0, 30, 60 deg, no elevation.
  for (int b = 0; b < 5; ++b) {
    const Eigen::Vector3d& v = d[5 + b];
    EXPECT_NEAR(std::atan2(v.y(), v.x()), (-60.0 + 30.0 * b) * kDeg, 1e-9);
    EXPECT_NEAR(v.z(), 0.0, 1e-12);
  }
  // Rows from the upper edge (-10 deg, z < 0 is up) to the lower (+10 deg) on the centre beam.
  EXPECT_NEAR(std::asin(d[2].z()), -10 * kDeg, 1e-9);
  EXPECT_NEAR(std::asin(d[12].z()), 10 * kDeg, 1e-9);
  // The centre beam of the mounting's axis row points pitch_deg below the horizontal.
  const Eigen::Vector3d axis = o.mounting().linear() * d[7];
  EXPECT_NEAR(std::asin(axis.z()), o.mount_pitch, 1e-9);
  EXPECT_NEAR(axis.y(), 0.0, 1e-12);
}

TEST(MultibeamTest, SeabedReturnsLieOnTheSeabedAtTheExpectedRange) {
  const World world = emptyWorld();
  MultibeamOptions o = quietFan();
  o.beams = 9;
  o.rows = 1;
  o.mount_position = Eigen::Vector3d::Zero();
  o.mount_pitch = 30 * kDeg;
  Multibeam sonar(o, 1);
  const double altitude = 5.0;  // vehicle at 15 m over a seabed at 20 m
  const Eigen::Isometry3d pose = vehiclePose({0, 0, 15}, 0.7);
  const SensorCloud cloud = sonar.ping(pose, 0.0, world.caster, 20.0);
  ASSERT_EQ(cloud.points.size(), 9u);
  EXPECT_EQ(cloud.returns(), 9u);
  for (const Eigen::Vector3f& p : cloud.points) {
    EXPECT_NEAR((pose * p.cast<double>()).z(), 20.0, 1e-4);  // on the seabed
  }
  // The centre beam meets the seabed at altitude / sin(pitch).
  EXPECT_NEAR(cloud.points[4].norm(), altitude / std::sin(30 * kDeg), 1e-4);
  EXPECT_NEAR(cloud.max_range, o.max_range, 0.0);
}

TEST(MultibeamTest, ReturnsFromABoxAheadAndNoneWhereThereIsNothing) {
  // A box face 6 m ahead reaching from 12 m to 30 m depth; vehicle at 10 m looking level.
  const World world(test::box({6, -50, 12}, {7, 50, 30}));
  MultibeamOptions o = quietFan();
  o.beams = 3;
  o.rows = 2;
  o.horizontal_aperture = 40 * kDeg;
  o.vertical_aperture = 60 * kDeg;  // rows at -30 deg (up) and +30 deg (down) from the axis
  o.mount_position = Eigen::Vector3d::Zero();
  o.mount_pitch = 0.0;
  o.max_range = 20.0;
  Multibeam sonar(o, 1);
  const SensorCloud cloud = sonar.ping(vehiclePose({0, 0, 10}, 0.0), 0.0, world.caster, 100.0);
  ASSERT_EQ(cloud.points.size(), 6u);
  for (int b = 0; b < 3; ++b) {
    // Upper row: over the box (the face starts at 12 m depth, the ray reaches 12 m only
    // 3.5 m ahead) and up to the surface: no return, a point past max_range.
    EXPECT_EQ(cloud.intensities[b], 0.0f);
    EXPECT_GT(cloud.points[b].norm(), o.max_range);
    // Lower row: hits the face x = 6 (at 10 + 6 tan 30 = 13.5 m depth, on the face).
    EXPECT_GT(cloud.intensities[3 + b], 0.0f);
    EXPECT_NEAR(cloud.points[3 + b].x(), 6.0, 1e-4);
  }
}

TEST(MultibeamTest, RangeNoiseAndBlanking) {
  const World world = emptyWorld();
  MultibeamOptions o = quietFan();
  o.beams = 64;
  o.rows = 1;
  o.mount_position = Eigen::Vector3d::Zero();
  o.mount_pitch = 90 * kDeg;  // straight down: every beam sees the seabed
  o.horizontal_aperture = 1 * kDeg;
  o.range_noise = 0.1;
  Multibeam noisy(o, 7);
  const SensorCloud cloud = noisy.ping(vehiclePose({0, 0, 10}, 0.0), 0.0, world.caster, 20.0);
  double sum = 0.0, sum2 = 0.0;
  for (const Eigen::Vector3f& p : cloud.points) {
    const double e = p.norm() - 10.0;
    sum += e;
    sum2 += e * e;
  }
  const double sigma = std::sqrt(sum2 / 64 - (sum / 64) * (sum / 64));
  EXPECT_GT(sigma, 0.05);
  EXPECT_LT(sigma, 0.2);
  // The seabed 0.3 m below is inside the blanking distance: the beams are left out (they saw
  // something, not free water).
  o.range_noise = 0.0;
  o.min_range = 0.5;
  Multibeam blanked(o, 7);
  EXPECT_TRUE(blanked.ping(vehiclePose({0, 0, 19.7}, 0.0), 0.0, world.caster, 20.0).points.empty());
  // Grazing incidence beyond max_incidence: left out too. Pitched 10 deg down, the seabed is
  // met 80 deg from its normal.
  o.mount_pitch = 10 * kDeg;
  o.max_incidence = 70 * kDeg;
  Multibeam grazing(o, 7);
  EXPECT_TRUE(grazing.ping(vehiclePose({0, 0, 18}, 0.0), 0.0, world.caster, 20.0).points.empty());
  o.max_incidence = 85 * kDeg;
  Multibeam steep_enough(o, 7);
  EXPECT_EQ(steep_enough.ping(vehiclePose({0, 0, 18}, 0.0), 0.0, world.caster, 20.0).returns(),
            64u);
}

TEST(MultibeamTest, PingsAtItsRate) {
  MultibeamOptions o = quietFan();
  o.rate = 10.0;
  o.beams = 4;
  Multibeam sonar(o, 1);
  const World world = emptyWorld();
  int pings = 0;
  for (int step = 0; step < 100; ++step) {  // 2 s at 50 Hz
    const double t = step * 0.02;
    if (sonar.due(t)) {
      sonar.ping(vehiclePose({0, 0, 10}, 0), t, world.caster, 20.0);
      ++pings;
    }
  }
  EXPECT_EQ(pings, 20);
}

TEST(DvlBeamsTest, JanusGeometry) {
  DvlBeamsOptions o;
  o.enabled = true;
  const DvlBeams dvl(o, 1);
  ASSERT_EQ(dvl.beamDirections().size(), 4u);
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d& d = dvl.beamDirections()[k];
    EXPECT_NEAR(d.norm(), 1.0, 1e-12);
    EXPECT_NEAR(std::acos(d.z()), 30 * kDeg, 1e-9);  // from the vertical
    EXPECT_NEAR(std::atan2(d.y(), d.x()), (45.0 + 90.0 * k - (k >= 2 ? 360.0 : 0.0)) * kDeg,
                1e-9);  // 45, 135, -135, -45 deg
  }
}

TEST(DvlBeamsTest, FlatSeabedRangeIsAltitudeOverCos30) {
  const World world = emptyWorld();
  DvlBeamsOptions o;
  o.enabled = true;
  o.range_noise = 0.0;
  o.mount_position = Eigen::Vector3d::Zero();
  DvlBeams dvl(o, 1);
  const double altitude = 4.0;
  const Eigen::Isometry3d pose = vehiclePose({3, -2, 20.0 - altitude}, 1.1);
  const SensorCloud cloud = dvl.ping(pose, 0.0, world.caster, 20.0);
  ASSERT_EQ(cloud.points.size(), 4u);
  EXPECT_EQ(cloud.returns(), 4u);
  for (int k = 0; k < 4; ++k) {
    EXPECT_NEAR(cloud.points[k].norm(), altitude / std::cos(30 * kDeg), 1e-4);
    EXPECT_NEAR((pose * cloud.points[k].cast<double>()).z(), 20.0, 1e-4);
    EXPECT_NEAR(cloud.intensities[k], std::cos(30 * kDeg), 1e-5);  // incidence 30 deg
  }
  // Over a rock (a box top 1.5 m below the vehicle) the beams return from the rock.
  const World rock(test::box({-10, -10, 17.5}, {10, 10, 20}));
  DvlBeams over_rock(o, 1);
  const SensorCloud on_rock = over_rock.ping(vehiclePose({0, 0, 16}, 0.0), 0.0, rock.caster, 20.0);
  for (const Eigen::Vector3f& p : on_rock.points) {
    EXPECT_NEAR(p.norm(), 1.5 / std::cos(30 * kDeg), 1e-4);
  }
  // Beyond max_range: no returns, points past max_range.
  o.max_range = 3.0;
  DvlBeams short_range(o, 1);
  const SensorCloud none = short_range.ping(pose, 0.0, world.caster, 20.0);
  EXPECT_EQ(none.returns(), 0u);
  for (const Eigen::Vector3f& p : none.points) EXPECT_GT(p.norm(), 3.0);
}

TEST(SensorOptionsTest, AbsentOrDisabledSectionsMeanNoSensor) {
  EXPECT_FALSE(MultibeamOptions::fromScenario(scenarioText("name: x\n")).enabled);
  EXPECT_FALSE(DvlBeamsOptions::fromScenario(scenarioText("name: x\n")).enabled);
  EXPECT_FALSE(
      MultibeamOptions::fromScenario(scenarioText("multibeam: {enabled: false}\n")).enabled);
  // A disabled section is not checked further (so it can be switched off in place).
  EXPECT_FALSE(MultibeamOptions::fromScenario(
                   scenarioText("multibeam: {enabled: false, horizontal_aperture_deg: 200}\n"))
                   .enabled);
  const MultibeamOptions on = MultibeamOptions::fromScenario(
      scenarioText("multibeam: {beams: 128, rows: 2, pitch_deg: 20, rate: 15}\n"));
  EXPECT_TRUE(on.enabled);
  EXPECT_EQ(on.beams, 128);
  EXPECT_EQ(on.rows, 2);
  EXPECT_NEAR(on.mount_pitch, 20 * kDeg, 1e-12);
  EXPECT_NEAR(on.rate, 15.0, 0.0);
  EXPECT_TRUE(MultibeamOptions::fromScenario(scenarioText("multibeam:\n")).enabled);
  EXPECT_TRUE(DvlBeamsOptions::fromScenario(scenarioText("dvl_beams: {rate: 4}\n")).enabled);
}

TEST(SensorOptionsTest, BadValuesNameFileAndField) {
  const struct {
    const char* yaml;
    const char* field;
  } cases[] = {
      {"multibeam: {horizontal_aperture_deg: 200}\n", "multibeam.horizontal_aperture_deg"},
      {"multibeam: {rate: 0}\n", "multibeam.rate"},
      {"multibeam: {rate: -5}\n", "multibeam.rate"},
      {"multibeam: {max_range: 0}\n", "multibeam.max_range"},
      {"multibeam: {max_range: 1, min_range: 2}\n", "multibeam.max_range"},
      {"multibeam: {beams: 0}\n", "multibeam.beams"},
      {"multibeam: {rows: 0}\n", "multibeam.rows"},
      {"multibeam: {rows: 3, vertical_aperture_deg: 0}\n", "multibeam.vertical_aperture_deg"},
      {"multibeam: {range_noise: -1}\n", "multibeam.range_noise"},
      {"multibeam: {rate: 40}\n", "multibeam.rate"},  // echo from 30 m needs 40 ms
      {"multibeam: {beam: 10}\n", "multibeam.beam"},  // misspelt key
      {"multibeam: {enabled: maybe}\n", "multibeam.enabled"},
      {"dvl_beams: {beam_angle_deg: 95}\n", "dvl_beams.beam_angle_deg"},
      {"dvl_beams: {rate: 0}\n", "dvl_beams.rate"},
      {"dvl_beams: {max_range: -3}\n", "dvl_beams.max_range"},
  };
  for (const auto& c : cases) {
    const std::string error = errorOf(c.yaml);
    EXPECT_NE(error.find("scenario.yaml"), std::string::npos) << c.yaml << " -> " << error;
    EXPECT_NE(error.find(c.field), std::string::npos) << c.yaml << " -> " << error;
    EXPECT_EQ(error.find('\n'), std::string::npos) << error;  // one line
  }
}

}  // namespace
}  // namespace auv::sim
