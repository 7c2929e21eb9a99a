// Tests of the profiling sonar against analytic geometry (walls and a box built here).

#include "auv/sim/sensors/profiling_sonar.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "auv/msg/sensors.h"
#include "auv/sim/vehicle/vehicle.h"

namespace auv::sim {
namespace {

constexpr double kDeg = M_PI / 180.0;

static_assert(sonar_flags::kEchoReturned == auv::msg::SONAR_BEAM_ECHO_RETURNED);
static_assert(sonar_flags::kSaturated == auv::msg::SONAR_BEAM_SATURATED);
static_assert(sonar_flags::kScanStart == auv::msg::SONAR_BEAM_SCAN_START);

// A mesh and its ray caster (which keeps a reference to the mesh).
struct World {
  explicit World(Mesh m) : mesh(std::move(m)), caster(mesh) {}
  Mesh mesh;
  RayCaster caster;
};

void addQuad(Mesh& mesh, const Eigen::Vector3f& a, const Eigen::Vector3f& b,
             const Eigen::Vector3f& c, const Eigen::Vector3f& d) {
  const int base = static_cast<int>(mesh.vertices.size());
  for (const Eigen::Vector3f& v : {a, b, c, d}) {
    mesh.vertices.push_back(v);
    mesh.vertex_colors.emplace_back(0.5f, 0.5f, 0.5f);
  }
  mesh.triangles.emplace_back(base, base + 1, base + 2);
  mesh.triangles.emplace_back(base, base + 2, base + 3);
}

// A large vertical wall through `point` whose horizontal normal is at `normal_yaw` (rad, NED).
Mesh wall(const Eigen::Vector3d& point, double normal_yaw) {
  const Eigen::Vector3f p = point.cast<float>();
  const Eigen::Vector3f along(-std::sin(normal_yaw), std::cos(normal_yaw), 0.0f);
  const Eigen::Vector3f down(0, 0, 1);
  const float half = 200.0f;
  Mesh mesh;
  addQuad(mesh, p - half * along - half * down, p + half * along - half * down,
          p + half * along + half * down, p - half * along + half * down);
  return mesh;
}

// An axis-aligned box (NED).
Mesh box(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) {
  auto corner = [&](int i) {
    return Eigen::Vector3f(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(),
                           i & 4 ? hi.z() : lo.z());
  };
  Mesh mesh;
  const int faces[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1},
                           {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
  for (const auto& f : faces) addQuad(mesh, corner(f[0]), corner(f[1]), corner(f[2]), corner(f[3]));
  return mesh;
}

// A narrow pencil: one ray on the axis, so ranges follow the axis geometry exactly.
SonarOptions pencilOptions() {
  SonarOptions o;
  o.rays_horizontal = 1;
  o.rays_vertical = 1;
  o.false_return_probability = 0.0;
  return o;
}

Eigen::Isometry3d vehiclePose(const Eigen::Vector3d& position, double yaw) {
  VehicleState state;
  state.position = position;
  state.yaw = yaw;
  return state.pose();
}

// Pings `count` times at the sonar's own rate from a fixed pose.
std::vector<SonarPing> pingMany(ProfilingSonar& sonar, const Eigen::Isometry3d& pose,
                                const RayCaster& world, int count) {
  std::vector<SonarPing> pings;
  for (int i = 0; i < count; ++i) {
    pings.push_back(sonar.ping(pose, i == 0 ? 0.0 : sonar.nextPingTime(), world));
  }
  return pings;
}

TEST(ProfilingSonar, WallRangeFollowsGeometryWithinNoise) {
  // The head (mounted 0.55 m forward, 0.15 m up) faces a wall 10 m ahead of it.
  SonarOptions options = pencilOptions();
  options.continuous = false;
  options.sector_left = -40 * kDeg;
  options.sector_right = 40 * kDeg;
  const double head_x = options.mount_position.x();
  World world(wall(Eigen::Vector3d(head_x + 10.0, 0, 0), 0.0));
  const double spacing = options.rangeResolution() / 8;
  const double tolerance = 4 * options.range_noise + 2 * spacing;
  for (bool pencil : {true, false}) {
    SonarOptions o = options;
    if (!pencil) {  // the default 3 x 7 ray beam: the first return is the nearest part in it
      o.rays_horizontal = SonarOptions().rays_horizontal;
      o.rays_vertical = SonarOptions().rays_vertical;
    }
    ProfilingSonar sonar(o, 1);
    const auto pings = pingMany(sonar, vehiclePose({0, 0, 3}, 0.0), world.caster, 46);
    for (const SonarPing& ping : pings) {
      ASSERT_TRUE(ping.echo()) << "angle " << ping.angle;
      ASSERT_EQ(ping.ranges.size(), 1u);
      ASSERT_EQ(ping.intensities.size(), 1u);
      const double axis_range = 10.0 / std::cos(ping.angle);
      const double nearest_in_beam =
          10.0 / std::cos(std::max(0.0, std::abs(ping.angle) - o.horizontal_beam_width / 2));
      const double low = pencil ? axis_range : nearest_in_beam;
      EXPECT_GT(ping.ranges[0], low - tolerance) << "angle " << ping.angle / kDeg;
      EXPECT_LT(ping.ranges[0], axis_range + tolerance) << "angle " << ping.angle / kDeg;
    }
  }
}

TEST(ProfilingSonar, NothingWithinRangeGivesNoEcho) {
  SonarOptions options = pencilOptions();
  options.rays_horizontal = 3;
  options.rays_vertical = 7;
  World world(wall(Eigen::Vector3d(options.max_range + 5.0, 0, 0), 0.0));
  ProfilingSonar sonar(options, 2);
  for (const SonarPing& ping : pingMany(sonar, vehiclePose({0, 0, 3}, 0.0), world.caster, 250)) {
    EXPECT_FALSE(ping.echo());
    EXPECT_TRUE(ping.ranges.empty());
    EXPECT_TRUE(ping.intensities.empty());
    ASSERT_EQ(ping.bins.size(), static_cast<size_t>(options.bins));
    for (uint8_t b : ping.bins) ASSERT_LT(b, options.detection_threshold);
  }
}

TEST(ProfilingSonar, BlankedTargetShadowsTheBeam) {
  // A wall inside the blanking distance hides a wall 5 m away behind it.
  SonarOptions options = pencilOptions();
  const double head_x = options.mount_position.x();
  Mesh mesh = wall(Eigen::Vector3d(head_x + 0.5 * options.min_range, 0, 0), 0.0);
  const Mesh far = wall(Eigen::Vector3d(head_x + 5.0, 0, 0), 0.0);
  appendMesh(mesh, far);
  World world(std::move(mesh));
  ProfilingSonar sonar(options, 3);
  const SonarPing ping = sonar.ping(vehiclePose({0, 0, 3}, 0.0), 0.0, world.caster);
  EXPECT_NEAR(ping.angle, 0.0, 1e-12);
  EXPECT_FALSE(ping.echo());
}

TEST(ProfilingSonar, ContinuousHeadStepsAndFlagsEachRevolution) {
  World world(wall(Eigen::Vector3d(10, 0, 0), 0.0));
  for (double step_deg : {1.8, 7.0}) {
    SonarOptions options = pencilOptions();
    options.step_angle = step_deg * kDeg;
    ProfilingSonar sonar(options, 4);
    const auto pings = pingMany(sonar, vehiclePose({0, 0, 3}, 0.0), world.caster, 401);
    for (size_t i = 0; i < pings.size(); ++i) {
      EXPECT_NEAR(std::remainder(pings[i].angle - i * options.step_angle, 2 * M_PI), 0.0, 1e-9);
      EXPECT_GT(pings[i].angle, -M_PI);
      EXPECT_LE(pings[i].angle, M_PI);
      // A revolution starts on the first ping at or past each multiple of 360 deg.
      const bool expected = i == 0 || std::floor(i * step_deg / 360.0 + 1e-9) >
                                          std::floor((i - 1) * step_deg / 360.0 + 1e-9);
      EXPECT_EQ(bool(pings[i].flags & sonar_flags::kScanStart), expected) << "ping " << i;
    }
    if (step_deg == 1.8) {  // 200 steps per turn exactly
      EXPECT_TRUE(pings[200].flags & sonar_flags::kScanStart);
      EXPECT_FALSE(pings[199].flags & sonar_flags::kScanStart);
      EXPECT_TRUE(pings[400].flags & sonar_flags::kScanStart);
    }
  }
}

TEST(ProfilingSonar, SectorHeadSweepsBackAndForthBetweenLimits) {
  World world(wall(Eigen::Vector3d(10, 0, 0), 0.0));
  SonarOptions options = pencilOptions();
  options.continuous = false;
  options.sector_left = -30 * kDeg;
  options.sector_right = 30 * kDeg;
  ProfilingSonar sonar(options, 5);
  const auto pings = pingMany(sonar, vehiclePose({0, 0, 3}, 0.0), world.caster, 200);
  EXPECT_NEAR(pings[0].angle, options.sector_left, 1e-12);
  int left_hits = 0, right_hits = 0, reversals = 0;
  for (size_t i = 0; i < pings.size(); ++i) {
    const double a = pings[i].angle;
    EXPECT_GE(a, options.sector_left - 1e-12);
    EXPECT_LE(a, options.sector_right + 1e-12);
    left_hits += std::abs(a - options.sector_left) < 1e-12;
    right_hits += std::abs(a - options.sector_right) < 1e-12;
    bool reversed = false;
    if (i >= 1) {
      EXPECT_LE(std::abs(a - pings[i - 1].angle), options.step_angle + 1e-12);
    }
    if (i >= 2) {
      const double before = pings[i - 1].angle - pings[i - 2].angle;
      const double now = a - pings[i - 1].angle;
      reversed = before * now < 0;
    }
    reversals += reversed;
    EXPECT_EQ(bool(pings[i].flags & sonar_flags::kScanStart), i == 0 || reversed) << "ping " << i;
  }
  // 60 deg / 1.8 deg = 33.3 steps: 34 steps per sweep, so 200 pings make 5 reversals.
  EXPECT_EQ(reversals, 5);
  EXPECT_EQ(left_hits, 3);
  EXPECT_EQ(right_hits, 3);
}

TEST(ProfilingSonar, FalseReturnRateMatchesItsProbability) {
  World world(wall(Eigen::Vector3d(100, 0, 0), 0.0));  // open water within range
  SonarOptions options = pencilOptions();
  options.false_return_probability = 0.1;
  ProfilingSonar sonar(options, 6);
  const int kPings = 3000;
  int echoes = 0;
  double range_sum = 0;
  for (const SonarPing& ping : pingMany(sonar, vehiclePose({0, 0, 3}, 0.0), world.caster, kPings)) {
    if (!ping.echo()) continue;
    ++echoes;
    range_sum += ping.ranges[0];
    EXPECT_GE(ping.ranges[0], options.min_range);
    EXPECT_LE(ping.ranges[0], options.max_range);
  }
  const double p = options.false_return_probability;
  EXPECT_NEAR(echoes / double(kPings), p, 4 * std::sqrt(p * (1 - p) / kPings));
  // Uniform over the range window: mean near its middle (sd of the mean ~0.33 m here).
  EXPECT_NEAR(range_sum / echoes, 0.5 * (options.min_range + options.max_range), 1.5);
}

TEST(ProfilingSonar, PingTimesFollowThePingRate) {
  World world(wall(Eigen::Vector3d(10, 0, 0), 0.0));
  for (double rate : {0.0, 10.0}) {
    SonarOptions options = pencilOptions();
    options.ping_rate = rate;
    const double expected_rate = rate > 0 ? rate : 1.0 / (2 * options.max_range / 1500.0 + 0.013);
    EXPECT_NEAR(options.effectivePingRate(), expected_rate, 1e-9);
    ProfilingSonar sonar(options, 7);
    std::vector<double> stamps;
    const double kStep = 0.001;
    for (int i = 0; i <= 4000; ++i) {  // 4 s in 1 ms steps
      const double t = i * kStep;
      if (sonar.due(t))
        stamps.push_back(sonar.ping(vehiclePose({0, 0, 3}, 0), t, world.caster).stamp);
    }
    const double period = 1.0 / expected_rate;
    EXPECT_NEAR(stamps.size(), 4.0 / period + 1, 1.0);
    for (size_t i = 1; i < stamps.size(); ++i) {
      EXPECT_NEAR(stamps[i] - stamps[i - 1], period, kStep + 1e-9);
    }
    EXPECT_NEAR(stamps.back() - stamps.front(), (stamps.size() - 1) * period, kStep + 1e-9);
  }
}

TEST(ProfilingSonar, SameSeedGivesSamePings) {
  World world(box({6, -4, 0}, {9, 4, 8}));
  SonarOptions options;  // default beam, noise and false returns
  options.false_return_probability = 0.2;
  auto run = [&](uint64_t seed) {
    ProfilingSonar sonar(options, seed);
    std::vector<float> ranges;
    std::vector<uint8_t> bins;
    for (const SonarPing& ping : pingMany(sonar, vehiclePose({0, 0, 3}, 0.2), world.caster, 300)) {
      ranges.push_back(ping.echo() ? ping.ranges[0] : -1.0f);
      bins.insert(bins.end(), ping.bins.begin(), ping.bins.end());
    }
    return std::make_pair(ranges, bins);
  };
  const auto a = run(11), b = run(11), c = run(12);
  EXPECT_EQ(a.first, b.first);
  EXPECT_EQ(a.second, b.second);
  EXPECT_NE(a.first, c.first);
}

TEST(ProfilingSonar, BoxEchoesWhereTheGeometrySaysFromARotatedVehicle) {
  const Eigen::Vector3f lo(6, 2, 0), hi(10, 7, 8);
  World world(box(lo, hi));
  SonarOptions options = pencilOptions();
  options.mount_yaw = 25 * kDeg;
  ProfilingSonar sonar(options, 8);
  const Eigen::Isometry3d body = vehiclePose({1, -1, 3}, -0.7);
  int echoes = 0, checked = 0;
  for (const SonarPing& ping : pingMany(sonar, body, world.caster, 200)) {
    // The axis ray in the world, against the box by the slab method.
    const Eigen::Isometry3d head = body * ping.mounting;
    const Eigen::Vector3d origin = head.translation();
    const Eigen::Vector3d dir = head.linear() * ping.direction();
    double t_near = -1e9, t_far = 1e9;
    int face_axis = -1;
    for (int k = 0; k < 3; ++k) {
      if (std::abs(dir[k]) < 1e-12) {
        if (origin[k] < lo[k] || origin[k] > hi[k]) t_near = 1e9;
        continue;
      }
      double t0 = (lo[k] - origin[k]) / dir[k], t1 = (hi[k] - origin[k]) / dir[k];
      if (t0 > t1) std::swap(t0, t1);
      if (t0 > t_near) t_near = t0, face_axis = k;
      t_far = std::min(t_far, t1);
    }
    const bool geometric_hit = t_near <= t_far && t_near > 0 && t_near < options.max_range;
    if (!geometric_hit) {
      EXPECT_FALSE(ping.echo()) << "angle " << ping.angle / kDeg;
      continue;
    }
    const double cos_incidence = std::abs(dir[face_axis]);
    if (cos_incidence < 0.35) continue;  // near grazing: too weak to detect, skip
    ++checked;
    ASSERT_TRUE(ping.echo()) << "angle " << ping.angle / kDeg;
    ++echoes;
    EXPECT_NEAR(ping.ranges[0], t_near, 4 * options.range_noise + 0.03);
    // The reported point (mounting, head angle, range) lies on the box surface.
    const Eigen::Vector3d point = body * ping.pointInBody(ping.ranges[0]);
    EXPECT_NEAR((point - (origin + t_near * dir)).norm(), 0.0, 4 * options.range_noise + 0.03);
  }
  EXPECT_GT(checked, 15);
  EXPECT_EQ(echoes, checked);
}

TEST(ProfilingSonar, EchoStrengthFollowsIncidenceAndSaturates) {
  SonarOptions options = pencilOptions();
  options.noise_level = 0.0;
  options.gain = 0.8;
  options.detection_threshold = 10;
  options.range_noise = 0.0;
  const double head_x = options.mount_position.x();
  auto firstPing = [&](double normal_yaw, const SonarOptions& o) {
    World world(wall(Eigen::Vector3d(head_x + 10.0, 0, 0), normal_yaw));
    ProfilingSonar sonar(o, 9);
    return sonar.ping(vehiclePose({0, 0, 3}, 0.0), 0.0, world.caster);
  };
  const SonarPing straight = firstPing(0.0, options);
  const SonarPing oblique = firstPing(60 * kDeg, options);
  ASSERT_TRUE(straight.echo());
  ASSERT_TRUE(oblique.echo());
  // Lambert backscatter: strength ~ cos^2(incidence); 0.8 gain on a perpendicular wall.
  EXPECT_NEAR(straight.intensities[0], 0.8, 0.01);
  EXPECT_NEAR(oblique.intensities[0] / straight.intensities[0], 0.25, 0.01);
  EXPECT_NEAR(straight.ranges[0], 10.0, 0.03);
  EXPECT_NEAR(oblique.ranges[0], 10.0, 0.03);
  EXPECT_FALSE(straight.flags & sonar_flags::kSaturated);
  // The intensity profile peaks in the bin holding the wall.
  const int wall_bin = static_cast<int>((10.0 - options.min_range) / options.rangeResolution());
  const int peak_bin = static_cast<int>(
      std::max_element(straight.bins.begin(), straight.bins.end()) - straight.bins.begin());
  EXPECT_LE(std::abs(peak_bin - wall_bin), 1);

  SonarOptions loud = options;
  loud.gain = 4.0;
  const SonarPing saturated = firstPing(0.0, loud);
  EXPECT_TRUE(saturated.flags & sonar_flags::kSaturated);
  EXPECT_FLOAT_EQ(saturated.intensities[0], 1.0f);
  EXPECT_EQ(*std::max_element(saturated.bins.begin(), saturated.bins.end()), 255);
}

TEST(ProfilingSonar, PingCarriesTheSensorDescription) {
  World world(wall(Eigen::Vector3d(10, 0, 0), 0.0));
  SonarOptions options;
  options.mount_yaw = 0.4;
  ProfilingSonar sonar(options, 10);
  const SonarPing ping = sonar.ping(vehiclePose({0, 0, 3}, 0.0), 1.25, world.caster);
  EXPECT_DOUBLE_EQ(ping.stamp, 1.25);
  EXPECT_DOUBLE_EQ(ping.min_range, options.min_range);
  EXPECT_DOUBLE_EQ(ping.max_range, options.max_range);
  EXPECT_NEAR(ping.range_resolution * options.bins, options.max_range - options.min_range, 1e-9);
  EXPECT_DOUBLE_EQ(ping.sound_speed, 1500.0);
  EXPECT_NEAR(ping.horizontal_beam_width, 3 * kDeg, 1e-12);
  EXPECT_NEAR(ping.vertical_beam_width, 35 * kDeg, 1e-12);
  EXPECT_EQ(ping.bins.size(), static_cast<size_t>(options.bins));
  EXPECT_TRUE(ping.mounting.translation().isApprox(options.mount_position));
  EXPECT_NEAR(Eigen::AngleAxisd(Eigen::Matrix3d(ping.mounting.linear())).angle(), 0.4, 1e-12);
}

TEST(SonarOptions, ReadsYamlStrictly) {
  const YamlSection root(YAML::Load("sonar: {step_deg: 0.9, sector_deg: [-60, 45], "
                                    "max_range: 30, position: [0.5, 0, -0.2], yaw_deg: 90}"),
                         "", "test.yaml");
  const SonarOptions o = SonarOptions::fromYaml(root.child("sonar"));
  EXPECT_NEAR(o.step_angle, 0.9 * kDeg, 1e-12);
  EXPECT_FALSE(o.continuous);
  EXPECT_NEAR(o.sector_left, -60 * kDeg, 1e-12);
  EXPECT_NEAR(o.sector_right, 45 * kDeg, 1e-12);
  EXPECT_DOUBLE_EQ(o.max_range, 30.0);
  EXPECT_NEAR(o.mount_yaw, M_PI / 2, 1e-12);
  EXPECT_TRUE(o.mount_position.isApprox(Eigen::Vector3d(0.5, 0, -0.2)));
  EXPECT_TRUE(SonarOptions::fromYaml(YamlSection(YAML::Node(), "sonar", "x.yaml")).continuous);

  auto errorOf = [](const std::string& text) {
    const YamlSection r(YAML::Load(text), "", "test.yaml");
    try {
      SonarOptions::fromYaml(r.child("sonar"));
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(errorOf("sonar: {max_rnage: 10}").find("did you mean 'max_range'"), std::string::npos);
  EXPECT_NE(errorOf("sonar: {sector_deg: [30, -30]}").find("sonar.sector_deg"), std::string::npos);
  // 50 Hz at 20 m: the echo from max range (26.7 ms) would not be back before the next ping.
  EXPECT_NE(errorOf("sonar: {ping_rate: 50}").find("sonar.ping_rate"), std::string::npos);
  EXPECT_NE(errorOf("sonar: {min_range: 25}").find("sonar.max_range"), std::string::npos);
  EXPECT_NE(errorOf("sonar: {bins: 0}").find("test.yaml: sonar.bins"), std::string::npos);
}

}  // namespace
}  // namespace auv::sim
