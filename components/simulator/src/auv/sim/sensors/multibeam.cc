#include "auv/sim/sensors/multibeam.h"

#include <algorithm>
#include <cmath>

namespace auv::sim {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

void require(bool ok, const char* field, const char* what, double value) {
  requireOption(ok, std::string("multibeam.") + field, what, value);
}

bool positive(double x) { return std::isfinite(x) && x > 0.0; }
bool nonNegative(double x) { return std::isfinite(x) && x >= 0.0; }

// i-th of n values spread evenly over [-width/2, width/2] (the centre when n = 1).
double spread(int i, int n, double width) {
  return n > 1 ? -0.5 * width + width * static_cast<double>(i) / (n - 1) : 0.0;
}

// Row by row from the upper edge of the vertical aperture down, beams from port to starboard;
// checks the options first.
std::vector<Eigen::Vector3d> fanDirections(const MultibeamOptions& options) {
  options.check();
  std::vector<Eigen::Vector3d> directions;
  for (int r = 0; r < options.rows; ++r) {
    const double elevation = spread(r, options.rows, options.vertical_aperture);  // + = down
    for (int b = 0; b < options.beams; ++b) {
      const double azimuth = spread(b, options.beams, options.horizontal_aperture);
      directions.emplace_back(std::cos(elevation) * std::cos(azimuth),
                              std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
    }
  }
  return directions;
}

}  // namespace

Eigen::Isometry3d MultibeamOptions::mounting() const {
  // Pitching the head's x axis down in FRD is a negative rotation about y.
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(mount_yaw, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(-mount_pitch, Eigen::Vector3d::UnitY()))
                   .toRotationMatrix();
  T.translation() = mount_position;
  return T;
}

void MultibeamOptions::check() const {
  require(mount_position.allFinite(), "position", "finite numbers", mount_position.norm());
  require(std::isfinite(mount_pitch) && std::abs(mount_pitch) <= M_PI / 2, "pitch_deg",
          "a pitch in [-90, 90] deg", mount_pitch / kDegToRad);
  require(std::isfinite(mount_yaw) && std::abs(mount_yaw) <= 2 * M_PI, "yaw_deg",
          "a yaw in [-360, 360] deg", mount_yaw / kDegToRad);
  require(beams >= 1 && beams <= 4096, "beams", "1..4096 beams per row", beams);
  require(rows >= 1 && rows <= 64, "rows", "1..64 rows", rows);
  require(positive(horizontal_aperture) && horizontal_aperture <= M_PI + 1e-9,
          "horizontal_aperture_deg", "a fan in (0, 180] deg", horizontal_aperture / kDegToRad);
  require(nonNegative(vertical_aperture) && vertical_aperture <= M_PI + 1e-9,
          "vertical_aperture_deg", "an aperture in [0, 180] deg", vertical_aperture / kDegToRad);
  require(rows == 1 || vertical_aperture > 0.0, "vertical_aperture_deg",
          "an aperture > 0 deg when rows > 1", vertical_aperture / kDegToRad);
  require(nonNegative(min_range), "min_range", "a range >= 0 m", min_range);
  require(positive(max_range) && max_range > min_range, "max_range", "a range > min_range",
          max_range);
  require(positive(sound_speed), "sound_speed", "a speed > 0 m/s", sound_speed);
  require(positive(rate) && rate <= sound_speed / (2.0 * max_range) * (1.0 + 1e-9), "rate",
          "a rate > 0 Hz and <= sound_speed / (2 max_range) (the echo from max_range must "
          "return before the next ping)",
          rate);
  require(nonNegative(range_noise), "range_noise", "a sigma >= 0 m", range_noise);
  require(positive(max_incidence) && max_incidence <= M_PI / 2 + 1e-9, "max_incidence_deg",
          "an angle in (0, 90] deg", max_incidence / kDegToRad);
}

MultibeamOptions MultibeamOptions::fromYaml(const YamlSection& section, bool present) {
  section.rejectUnknownKeys({"enabled", "position", "pitch_deg", "yaw_deg", "beams", "rows",
                             "horizontal_aperture_deg", "vertical_aperture_deg", "rate",
                             "min_range", "max_range", "range_noise", "max_incidence_deg",
                             "sound_speed"});
  MultibeamOptions o;
  // A section that is there names a sensor that is there, unless it says otherwise.
  o.enabled = present;
  section.read("enabled", o.enabled);
  section.read("position", o.mount_position);
  section.readDegrees("pitch_deg", o.mount_pitch);
  section.readDegrees("yaw_deg", o.mount_yaw);
  section.read("beams", o.beams);
  section.read("rows", o.rows);
  section.readDegrees("horizontal_aperture_deg", o.horizontal_aperture);
  section.readDegrees("vertical_aperture_deg", o.vertical_aperture);
  section.read("rate", o.rate);
  section.read("min_range", o.min_range);
  section.read("max_range", o.max_range);
  section.read("range_noise", o.range_noise);
  section.readDegrees("max_incidence_deg", o.max_incidence);
  section.read("sound_speed", o.sound_speed);
  if (!o.enabled) return o;
  checkInFile(section, o);
  return o;
}

Multibeam::Multibeam(const MultibeamOptions& options, uint64_t seed)
    : options_(options), schedule_(options.rate), fan_(fanDirections(options), seed) {}

SensorCloud Multibeam::ping(const Eigen::Isometry3d& body_pose_true, double time,
                            const RayCaster& world, double seabed_depth) {
  const MultibeamOptions& o = options_;
  const BeamReturnModel model{o.min_range, o.max_range, o.range_noise, o.max_incidence};
  SensorCloud cloud = fan_.ping(o.mounting(), model, body_pose_true, time, world, seabed_depth);
  schedule_.fired(time);
  return cloud;
}

}  // namespace auv::sim
