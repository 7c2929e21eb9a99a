#include "bench_stream.h"

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include "auv/interfaces/msg_time.h"
#include "auv/mapping/components/message_conversions.h"

namespace auv::mapping::bench {
namespace {

constexpr double kHalfWidth = 8.0;           // m, canyon half width
constexpr double kFloorDepth = 6.0;          // m, floor below the vehicle
constexpr double kMaxRange = 20.0;           // m, sonar max range
constexpr double kSpeed = 1.5;               // m/s, along x
constexpr int64_t kPingPeriodNs = 20000000;  // 50 Hz profiler
constexpr double kStepRad = 0.9 * M_PI / 180.0;
constexpr double kTiltRad = 20.0 * M_PI / 180.0;
constexpr double kRangeNoise = 0.05;   // m, 1 sigma
constexpr double kSwathWidth = 2.4;    // rad, multibeam fan across the canyon
constexpr double kSwathSpacing = 0.2;  // m along x between swaths
constexpr int kBins = 200;             // intensity bins per beam, as the simulator sends
// Stamps start at 1000 s: a map update stamped 0 means "no measurement yet".
constexpr int64_t kEpochNs = 1000000000000;

// Range to the canyon walls/floor along `direction` from the vehicle, or infinity.
double rangeToCanyon(const Eigen::Vector3d& direction) {
  double range = std::numeric_limits<double>::infinity();
  if (std::abs(direction.y()) > 1e-9) range = std::min(range, kHalfWidth / std::abs(direction.y()));
  if (direction.z() > 1e-9) range = std::min(range, kFloorDepth / direction.z());
  return range;
}

msg::Pose pose(const Eigen::Vector3d& position, const Eigen::Quaterniond& orientation) {
  msg::Pose p;
  p.position().x(position.x());
  p.position().y(position.y());
  p.position().z(position.z());
  p.orientation().w(orientation.w());
  p.orientation().x(orientation.x());
  p.orientation().y(orientation.y());
  p.orientation().z(orientation.z());
  return p;
}

Eigen::Vector3d positionAt(int64_t stamp_ns) {
  return Eigen::Vector3d(kSpeed * 1e-9 * static_cast<double>(stamp_ns - kEpochNs), 0.0, 0.0);
}

// The multibeam scene: the simulator's default multibeam over a bouldery seabed.
constexpr double kMbSeabed = 6.0;                       // m below the vehicle
constexpr double kMbMaxRange = 30.0;                    // m
constexpr double kMbRate = 10.0;                        // Hz
constexpr double kMbHorizontal = 120.0 * M_PI / 180.0;  // rad
constexpr double kMbVertical = 20.0 * M_PI / 180.0;     // rad
constexpr double kMbPitch = 25.0 * M_PI / 180.0;        // rad, down
constexpr double kMbNoReturn = 1.5;                     // x max range, as the simulator

struct Boulder {
  Eigen::Vector3d centre;
  double radius;
};

// Range along unit `d` from `o` to the seabed plane or the first boulder, or infinity.
double rangeToBoulders(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                       const std::vector<Boulder>& boulders) {
  double range =
      d.z() > 1e-9 ? (kMbSeabed - o.z()) / d.z() : std::numeric_limits<double>::infinity();
  for (const Boulder& b : boulders) {
    const Eigen::Vector3d oc = o - b.centre;
    const double half_b = oc.dot(d);
    const double disc = half_b * half_b - (oc.squaredNorm() - b.radius * b.radius);
    if (disc < 0) continue;
    const double t = -half_b - std::sqrt(disc);
    if (t > 0 && t < range) range = t;
  }
  return range;
}

void addMultibeamSwaths(const StreamOptions& options, std::mt19937& random, Stream& stream) {
  std::normal_distribution<double> noise(0.0, kRangeNoise);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const double length = kSpeed * static_cast<double>(options.swaths) / kMbRate + 40.0;
  std::vector<Boulder> boulders;  // about one per 25 m^2 over a 50 m wide strip
  for (int k = 0; k < static_cast<int>(length * 50.0 / 25.0); ++k) {
    const double radius = 0.5 + 2.0 * uniform(random);
    // Tops from 0.5 m to 4.5 m above the seabed: some within 2 m of the vehicle's depth.
    const double top = kMbSeabed - 0.5 - 4.0 * uniform(random);
    boulders.push_back(
        {{-5.0 + length * uniform(random), -25.0 + 50.0 * uniform(random), top + radius}, radius});
  }
  const Eigen::Matrix3d pitch =
      Eigen::AngleAxisd(-kMbPitch, Eigen::Vector3d::UnitY()).toRotationMatrix();
  std::vector<Eigen::Vector3d> fan;
  for (std::size_t r = 0; r < options.rows; ++r) {
    const double e = options.rows > 1 ? -kMbVertical / 2 + kMbVertical * r / (options.rows - 1) : 0;
    for (std::size_t b = 0; b < options.points; ++b) {
      const double a = -kMbHorizontal / 2 + kMbHorizontal * b / (options.points - 1);
      fan.push_back(pitch * Eigen::Vector3d(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a),
                                            std::sin(e)));
    }
  }
  stream.cloud_max_range = kMbMaxRange;
  stream.points_per_cloud = fan.size();
  for (std::size_t s = 0; s < options.swaths; ++s) {
    const double t = static_cast<double>(s) / kMbRate;
    const Eigen::Vector3d origin(kSpeed * t, 0.0, 0.0);
    msg::PointCloud cloud;
    cloud.header().stamp(interfaces::toMsgTime(kEpochNs + std::llround(1e9 * t)));
    cloud.header().frame_id("world");
    cloud.sensor_origin(pose(origin, Eigen::Quaterniond::Identity()));
    cloud.max_range(static_cast<float>(kMbMaxRange));
    std::vector<Eigen::Vector3d> points;
    octomap::Pointcloud raw;
    for (const Eigen::Vector3d& direction : fan) {
      const double hit = rangeToBoulders(origin, direction, boulders);
      const bool echo = hit <= kMbMaxRange;
      const double range = echo ? hit + noise(random) : kMbNoReturn * kMbMaxRange;
      const Eigen::Vector3d point = origin + range * direction;
      msg::PointXYZI p;
      p.x(static_cast<float>(point.x()));
      p.y(static_cast<float>(point.y()));
      p.z(static_cast<float>(point.z()));
      p.intensity(echo ? 0.8f : 0.0f);
      cloud.points().push_back(p);
      points.emplace_back(p.x(), p.y(), p.z());  // what the component gets: float coordinates
      raw.push_back(p.x(), p.y(), p.z());
    }
    stream.clouds.push_back(std::move(cloud));
    stream.cloud_points.push_back(std::move(points));
    stream.raw_clouds.push_back(std::move(raw));
    stream.cloud_origins.push_back(origin);
  }
}

}  // namespace

int64_t Stream::lastBeamStampNs() const {
  return beams.empty() ? 0 : interfaces::toNanoseconds(beams.back().header().stamp());
}

int64_t Stream::lastCloudStampNs() const {
  return clouds.empty() ? 0 : interfaces::toNanoseconds(clouds.back().header().stamp());
}

Stream makeStream(const StreamOptions& options) {
  if (options.odometry_rate <= 0 || options.points < 2 || options.rows < 1) {
    throw std::invalid_argument("makeStream: odometry_rate must be > 0, points >= 2 and rows >= 1");
  }
  if (options.swath_shape != "canyon" && options.swath_shape != "multibeam") {
    throw std::invalid_argument("makeStream: swath shape must be canyon or multibeam, got " +
                                options.swath_shape);
  }
  Stream stream;
  std::mt19937 random(options.seed);
  std::normal_distribution<double> noise(0.0, kRangeNoise);

  // Odometry up to (and including) the last beam's stamp, so that every beam can be placed.
  const int64_t odometry_period_ns = std::llround(1e9 / options.odometry_rate);
  const int64_t last_beam_ns =
      options.beams == 0 ? 0 : static_cast<int64_t>(options.beams - 1) * kPingPeriodNs;
  const int64_t odometry_count = last_beam_ns / odometry_period_ns + 2;
  PoseBuffer::Options buffer_options;
  buffer_options.capacity = static_cast<std::size_t>(odometry_count) + 2;
  PoseBuffer poses(buffer_options);
  for (int64_t k = 0; k < odometry_count; ++k) {
    const int64_t stamp = kEpochNs + k * odometry_period_ns;
    msg::Odometry odometry;
    odometry.header().stamp(interfaces::toMsgTime(stamp));
    odometry.header().frame_id("world");
    odometry.child_frame_id("base_link");
    odometry.pose().pose(pose(positionAt(stamp), Eigen::Quaterniond::Identity()));
    odometry.twist().twist().linear().x(kSpeed);
    odometry.altitude(kFloorDepth);
    odometry.source_flags(msg::ODOMETRY_SOURCE_DVL_VALID | msg::ODOMETRY_SOURCE_IMU);
    poses.add(toStampedPose(odometry));
    stream.odometry.push_back(std::move(odometry));
  }

  stream.beam_max_range = kMaxRange;
  std::size_t next_odometry = 0;
  for (std::size_t i = 0; i < options.beams; ++i) {
    const int64_t stamp = kEpochNs + static_cast<int64_t>(i) * kPingPeriodNs;
    // What the navigation has published by the time of the ping.
    while (next_odometry < stream.odometry.size() &&
           kEpochNs + static_cast<int64_t>(next_odometry) * odometry_period_ns <= stamp) {
      stream.events.push_back({Event::ODOMETRY, next_odometry++});
    }
    const double angle = std::remainder(static_cast<double>(i) * kStepRad, 2 * M_PI);
    const Eigen::Quaterniond mounting(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()) *
                                      Eigen::AngleAxisd(-kTiltRad, Eigen::Vector3d::UnitY()));
    msg::SonarBeam beam;
    beam.header().stamp(interfaces::toMsgTime(stamp));
    beam.header().frame_id("sonar");
    beam.mounting(pose(Eigen::Vector3d::Zero(), mounting));
    beam.beam_angle(0.0f);  // the head angle rides in the mounting (cone, see header)
    beam.horizontal_beam_width(static_cast<float>(3.0 * M_PI / 180.0));
    beam.vertical_beam_width(static_cast<float>(35.0 * M_PI / 180.0));
    beam.min_range(0.0f);  // raw insertPointCloud has no blanking distance
    beam.max_range(static_cast<float>(kMaxRange));
    beam.range_resolution(static_cast<float>(kMaxRange / kBins));
    beam.sound_speed(1500.0f);
    // The world ray exactly as the component will compute it.
    const auto body = poses.lookUp(stamp);
    if (!body) throw std::logic_error("makeStream: no pose for a beam");
    const Eigen::Isometry3d world_T_sensor = toIsometry(*body) * toIsometry(beam.mounting());
    const Eigen::Vector3d direction =
        (world_T_sensor.linear() * beamDirection(beam.beam_angle())).normalized();
    const double range = rangeToCanyon(direction) + noise(random);
    std::vector<uint8_t> bins(kBins, 3);
    if (range <= kMaxRange) {
      beam.ranges({static_cast<float>(range)});
      beam.range_intensities({0.8f});
      bins[std::min<std::size_t>(kBins - 1, static_cast<std::size_t>(range / kMaxRange * kBins))] =
          200;
      beam.flags(msg::SONAR_BEAM_ECHO_RETURNED);
    }
    beam.bins(std::move(bins));
    stream.beam_geometry.push_back(toGeometry(beam));
    stream.beam_world_T_sensor.push_back(world_T_sensor);
    // Raw baseline: the return, or a point past max range (with maxrange set it clears free
    // space only); the origin and direction as MapBuilder::insertBeam computes them.
    const Eigen::Vector3d origin = world_T_sensor.translation();
    const Eigen::Vector3d end =
        origin + stream.beam_geometry.back().return_range.value_or(kMaxRange + 1.0) * direction;
    stream.raw_beam_origins.emplace_back(static_cast<float>(origin.x()),
                                         static_cast<float>(origin.y()),
                                         static_cast<float>(origin.z()));
    stream.raw_beam_ends.emplace_back(static_cast<float>(end.x()), static_cast<float>(end.y()),
                                      static_cast<float>(end.z()));
    stream.events.push_back({Event::BEAM, i});
    stream.beams.push_back(std::move(beam));
  }
  while (next_odometry < stream.odometry.size()) {
    stream.events.push_back({Event::ODOMETRY, next_odometry++});
  }

  if (options.swath_shape == "multibeam") {
    addMultibeamSwaths(options, random, stream);
    return stream;
  }
  // Multibeam swaths: one world-frame cloud per swath, a vertical fan across the canyon.
  stream.cloud_max_range = kMaxRange;
  stream.points_per_cloud = options.points;
  for (std::size_t s = 0; s < options.swaths; ++s) {
    const Eigen::Vector3d origin(kSwathSpacing * static_cast<double>(s), 0.0, 0.0);
    msg::PointCloud cloud;
    cloud.header().stamp(interfaces::toMsgTime(
        kEpochNs + std::llround(1e9 * kSwathSpacing * static_cast<double>(s) / kSpeed)));
    cloud.header().frame_id("world");
    cloud.sensor_origin(pose(origin, Eigen::Quaterniond::Identity()));
    cloud.max_range(static_cast<float>(kMaxRange));
    std::vector<Eigen::Vector3d> points;
    octomap::Pointcloud raw;
    for (std::size_t k = 0; k < options.points; ++k) {
      const double across = -kSwathWidth / 2 + kSwathWidth * static_cast<double>(k) /
                                                   static_cast<double>(options.points - 1);
      const Eigen::Vector3d direction(0.0, std::sin(across), std::cos(across));
      const Eigen::Vector3d point = origin + (rangeToCanyon(direction) + noise(random)) * direction;
      msg::PointXYZI p;
      p.x(static_cast<float>(point.x()));
      p.y(static_cast<float>(point.y()));
      p.z(static_cast<float>(point.z()));
      p.intensity(0.8f);
      cloud.points().push_back(p);
      points.emplace_back(p.x(), p.y(), p.z());  // what the component gets: float coordinates
      raw.push_back(p.x(), p.y(), p.z());
    }
    stream.clouds.push_back(std::move(cloud));
    stream.cloud_points.push_back(std::move(points));
    stream.raw_clouds.push_back(std::move(raw));
    stream.cloud_origins.push_back(origin);
  }
  return stream;
}

}  // namespace auv::mapping::bench
