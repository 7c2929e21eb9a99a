#include "auv/sim/sensors/dvl_beams.h"

#include <algorithm>
#include <cmath>

namespace auv::sim {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

void require(bool ok, const char* field, const char* what, double value) {
  requireOption(ok, std::string("dvl_beams.") + field, what, value);
}

bool positive(double x) { return std::isfinite(x) && x > 0.0; }
bool nonNegative(double x) { return std::isfinite(x) && x >= 0.0; }

// The four Janus beams in azimuth order, `beam_angle` from the vertical; checks the options first.
std::vector<Eigen::Vector3d> janusDirections(const DvlBeamsOptions& options) {
  options.check();
  const double s = std::sin(options.beam_angle), c = std::cos(options.beam_angle);
  std::vector<Eigen::Vector3d> directions;
  for (int k = 0; k < DvlBeams::kBeams; ++k) {
    const double azimuth = options.azimuth_offset + k * M_PI / 2;
    directions.emplace_back(s * std::cos(azimuth), s * std::sin(azimuth), c);
  }
  return directions;
}

}  // namespace

Eigen::Isometry3d DvlBeamsOptions::mounting() const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = mount_position;
  return T;
}

void DvlBeamsOptions::check() const {
  require(mount_position.allFinite(), "position", "finite numbers", mount_position.norm());
  require(positive(beam_angle) && beam_angle < M_PI / 2, "beam_angle_deg",
          "an angle from the vertical in (0, 90) deg", beam_angle / kDegToRad);
  require(std::isfinite(azimuth_offset) && std::abs(azimuth_offset) <= 2 * M_PI,
          "azimuth_offset_deg", "an angle in [-360, 360] deg", azimuth_offset / kDegToRad);
  require(positive(rate) && rate <= 100.0, "rate", "a rate in (0, 100] Hz", rate);
  require(nonNegative(min_range), "min_range", "a range >= 0 m", min_range);
  require(positive(max_range) && max_range > min_range, "max_range", "a range > min_range",
          max_range);
  require(nonNegative(range_noise), "range_noise", "a sigma >= 0 m", range_noise);
}

DvlBeamsOptions DvlBeamsOptions::fromYaml(const YamlSection& section, bool present) {
  section.rejectUnknownKeys({"enabled", "position", "beam_angle_deg", "azimuth_offset_deg", "rate",
                             "min_range", "max_range", "range_noise"});
  DvlBeamsOptions o;
  o.enabled = present;  // a section that is there names an output that is there
  section.read("enabled", o.enabled);
  section.read("position", o.mount_position);
  section.readDegrees("beam_angle_deg", o.beam_angle);
  section.readDegrees("azimuth_offset_deg", o.azimuth_offset);
  section.read("rate", o.rate);
  section.read("min_range", o.min_range);
  section.read("max_range", o.max_range);
  section.read("range_noise", o.range_noise);
  if (!o.enabled) return o;
  checkInFile(section, o);
  return o;
}

DvlBeams::DvlBeams(const DvlBeamsOptions& options, uint64_t seed)
    : options_(options), schedule_(options.rate), fan_(janusDirections(options), seed) {}

SensorCloud DvlBeams::ping(const Eigen::Isometry3d& body_pose_true, double time,
                           const RayCaster& world, double seabed_depth) {
  const DvlBeamsOptions& o = options_;
  // Every bottom return echoes, however oblique (the default max_incidence).
  const BeamReturnModel model{o.min_range, o.max_range, o.range_noise};
  SensorCloud cloud = fan_.ping(o.mounting(), model, body_pose_true, time, world, seabed_depth);
  schedule_.fired(time);
  return cloud;
}

}  // namespace auv::sim
