#include "auv/sim/sensors/profiling_sonar.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

#include "auv/sim/vehicle/vehicle.h"

namespace auv::sim {
namespace {

constexpr double kDegToRad = M_PI / 180.0;
// The receiver envelope is sampled this many times per reported bin, so the leading edge of an
// echo is located to a fraction of a bin (a real profiler digitises faster than it reports).
constexpr int kOversampling = 8;
// s added to the two-way travel time per ping (head step, processing) for the automatic rate.
constexpr double kPingOverhead = 0.013;

void require(bool ok, const char* field, const char* what, double value) {
  requireOption(ok, std::string("sonar.") + field, what, value);
}

bool positive(double x) { return std::isfinite(x) && x > 0.0; }
bool nonNegative(double x) { return std::isfinite(x) && x >= 0.0; }

// Adds a rectangular echo of `amplitude` over [start, start + length) (m from the first sample)
// to an envelope sampled every `spacing` m, weighting partly covered samples by their overlap.
void depositPulse(std::vector<double>& envelope, double spacing, double start, double length,
                  double amplitude) {
  const double end = start + length;
  const int first = std::max(0, static_cast<int>(std::floor(start / spacing)));
  const int last =
      std::min(static_cast<int>(envelope.size()) - 1, static_cast<int>(std::floor(end / spacing)));
  for (int k = first; k <= last; ++k) {
    const double overlap =
        std::min(end, (k + 1) * spacing) - std::max(start, static_cast<double>(k) * spacing);
    if (overlap > 0.0) envelope[k] += amplitude * overlap / spacing;
  }
}

}  // namespace

double SonarOptions::effectivePingRate() const {
  if (ping_rate > 0.0) return ping_rate;
  return 1.0 / (2.0 * max_range / sound_speed + kPingOverhead);
}

Eigen::Isometry3d SonarOptions::mounting() const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(mount_yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = mount_position;
  return T;
}

void SonarOptions::check() const {
  require(mount_position.allFinite(), "position", "finite numbers", mount_position.norm());
  require(std::isfinite(mount_yaw), "yaw_deg", "a finite angle", mount_yaw);
  require(nonNegative(min_range), "min_range", "a range >= 0 m", min_range);
  require(positive(max_range) && max_range > min_range, "max_range", "a range > min_range",
          max_range);
  require(positive(step_angle) && step_angle <= M_PI, "step_deg", "a step in (0, 180] deg",
          step_angle / kDegToRad);
  if (!continuous) {
    require(std::isfinite(sector_left) && sector_left >= -M_PI - 1e-9, "sector_deg",
            "a left limit >= -180 deg", sector_left / kDegToRad);
    require(
        std::isfinite(sector_right) && sector_right <= M_PI + 1e-9 && sector_right > sector_left,
        "sector_deg", "a right limit > the left limit and <= 180 deg", sector_right / kDegToRad);
  }
  require(positive(sound_speed), "sound_speed", "a speed > 0 m/s", sound_speed);
  const double max_rate = sound_speed / (2.0 * max_range);
  require(nonNegative(ping_rate) && ping_rate <= max_rate * (1.0 + 1e-9), "ping_rate",
          "0 (automatic) or a rate <= sound_speed / (2 max_range) (the echo from max_range must "
          "return before the next ping)",
          ping_rate);
  require(positive(horizontal_beam_width) && horizontal_beam_width < M_PI,
          "horizontal_beam_width_deg", "a width in (0, 180) deg",
          horizontal_beam_width / kDegToRad);
  require(positive(vertical_beam_width) && vertical_beam_width < M_PI, "vertical_beam_width_deg",
          "a width in (0, 180) deg", vertical_beam_width / kDegToRad);
  require(rays_horizontal >= 1 && rays_horizontal <= 64, "rays_horizontal", "1..64",
          rays_horizontal);
  require(rays_vertical >= 1 && rays_vertical <= 64, "rays_vertical", "1..64", rays_vertical);
  require(nonNegative(range_noise), "range_noise", "a sigma >= 0 m", range_noise);
  require(std::isfinite(false_return_probability) && false_return_probability >= 0.0 &&
              false_return_probability <= 1.0,
          "false_return_probability", "a probability in [0, 1]", false_return_probability);
  require(bins >= 1 && bins <= 10000, "bins", "1..10000", bins);
  require(positive(detection_threshold) && detection_threshold <= 255.0, "detection_threshold",
          "a level in (0, 255]", detection_threshold);
  require(positive(gain), "gain", "a gain > 0", gain);
  require(nonNegative(noise_level), "noise_level", "a sigma >= 0", noise_level);
  require(positive(pulse_length) && pulse_length < max_range - min_range, "pulse_length",
          "a length > 0 m and < max_range - min_range", pulse_length);
}

SonarOptions SonarOptions::fromYaml(const YamlSection& section) {
  section.rejectUnknownKeys(
      {"position", "yaw_deg", "max_range", "min_range", "step_deg", "sector_deg", "ping_rate",
       "horizontal_beam_width_deg", "vertical_beam_width_deg", "rays_horizontal", "rays_vertical",
       "range_noise", "false_return_probability", "bins", "detection_threshold", "gain",
       "noise_level", "pulse_length", "sound_speed"});
  SonarOptions o;
  section.read("position", o.mount_position);
  section.readDegrees("yaw_deg", o.mount_yaw, -360.0, 360.0);
  section.read("max_range", o.max_range, 0.01);
  section.read("min_range", o.min_range, 0.0);
  section.readDegrees("step_deg", o.step_angle, 0.001, 180.0);
  if (section.has("sector_deg")) {
    std::vector<double> sector;
    section.read("sector_deg", sector);
    if (sector.size() != 2 || !(sector[0] < sector[1]) || sector[0] < -180.0 || sector[1] > 180.0) {
      section.fail("sector_deg",
                   "expected [left, right] in degrees with -180 <= left < right <= 180");
    }
    o.continuous = false;
    o.sector_left = sector[0] * kDegToRad;
    o.sector_right = sector[1] * kDegToRad;
  }
  section.read("ping_rate", o.ping_rate, 0.0);
  section.readDegrees("horizontal_beam_width_deg", o.horizontal_beam_width, 0.01, 179.0);
  section.readDegrees("vertical_beam_width_deg", o.vertical_beam_width, 0.01, 179.0);
  section.read("rays_horizontal", o.rays_horizontal, 1, 64);
  section.read("rays_vertical", o.rays_vertical, 1, 64);
  section.read("range_noise", o.range_noise, 0.0);
  section.read("false_return_probability", o.false_return_probability, 0.0, 1.0);
  section.read("bins", o.bins, 1, 10000);
  section.read("detection_threshold", o.detection_threshold, 1e-6, 255.0);
  section.read("gain", o.gain, 1e-6);
  section.read("noise_level", o.noise_level, 0.0);
  section.read("pulse_length", o.pulse_length, 1e-6);
  section.read("sound_speed", o.sound_speed, 1.0);
  checkInFile(section, o);
  return o;
}

Eigen::Vector3d SonarPing::direction() const {
  return Eigen::Vector3d(std::cos(angle), std::sin(angle), 0.0);
}

Eigen::Vector3d SonarPing::pointInBody(double range) const {
  return mounting * (range * direction());
}

ProfilingSonar::ProfilingSonar(const SonarOptions& options, uint64_t seed)
    : options_(options), rng_(seed) {
  options_.check();
  period_ = 1.0 / options_.effectivePingRate();
  sector_angle_ = options_.sector_left;

  // Rays at the cell centres of a grid over the -3 dB cone. Two-way beam pattern: a Gaussian
  // whose one-way power is -3 dB (1/2) at the half widths, so 1/4 there for transmit+receive.
  const int nh = options_.rays_horizontal, nv = options_.rays_vertical;
  double weight_sum = 0.0;
  for (int i = 0; i < nh; ++i) {
    for (int j = 0; j < nv; ++j) {
      const double azimuth = ((i + 0.5) / nh - 0.5) * options_.horizontal_beam_width;
      const double elevation = ((j + 0.5) / nv - 0.5) * options_.vertical_beam_width;
      const double a = azimuth / (0.5 * options_.horizontal_beam_width);
      const double e = elevation / (0.5 * options_.vertical_beam_width);
      const double weight = std::pow(4.0, -(a * a + e * e));
      ray_directions_.emplace_back(std::cos(elevation) * std::cos(azimuth),
                                   std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
      ray_weights_.push_back(weight);
      weight_sum += weight;
    }
  }
  for (double& w : ray_weights_) w /= weight_sum;
  envelope_.resize(static_cast<size_t>(options_.bins) * kOversampling);
}

double ProfilingSonar::headAngle() const {
  if (options_.continuous) {
    return wrapAngle(static_cast<double>(step_count_) * options_.step_angle);
  }
  return sector_angle_;
}

void ProfilingSonar::advanceHead() {
  if (options_.continuous) {
    ++step_count_;
    return;
  }
  // The head pings each limit once, then turns around.
  constexpr double kEps = 1e-9;
  reversed_ = false;
  if (direction_ > 0 && sector_angle_ >= options_.sector_right - kEps) {
    direction_ = -1;
    reversed_ = true;
  } else if (direction_ < 0 && sector_angle_ <= options_.sector_left + kEps) {
    direction_ = 1;
    reversed_ = true;
  }
  sector_angle_ = std::clamp(sector_angle_ + direction_ * options_.step_angle, options_.sector_left,
                             options_.sector_right);
}

SonarPing ProfilingSonar::ping(const Eigen::Isometry3d& body_pose_true, double time,
                               const RayCaster& world) {
  const SonarOptions& o = options_;
  SonarPing ping;
  ping.stamp = time;
  ping.angle = headAngle();
  ping.horizontal_beam_width = o.horizontal_beam_width;
  ping.vertical_beam_width = o.vertical_beam_width;
  ping.min_range = o.min_range;
  ping.max_range = o.max_range;
  ping.range_resolution = o.rangeResolution();
  ping.sound_speed = o.sound_speed;
  ping.mounting = o.mounting();

  bool scan_start = first_ping_;
  if (o.continuous && !first_ping_) {
    // A new revolution starts on the first ping at or past a multiple of 360 deg.
    const double turns = static_cast<double>(step_count_) * o.step_angle / (2.0 * M_PI);
    const double previous = static_cast<double>(step_count_ - 1) * o.step_angle / (2.0 * M_PI);
    scan_start = std::floor(turns + 1e-9) > std::floor(previous + 1e-9);
  } else if (!o.continuous) {
    scan_start = scan_start || reversed_;
  }
  if (scan_start) ping.flags |= sonar_flags::kScanStart;

  // Cast the beam from the head's true pose.
  const Eigen::Isometry3d head_to_world =
      body_pose_true * ping.mounting * Eigen::AngleAxisd(ping.angle, Eigen::Vector3d::UnitZ());
  const Eigen::Vector3f origin = head_to_world.translation().cast<float>();
  const size_t n_rays = ray_directions_.size();
  origins_.assign(n_rays, origin);
  directions_.resize(n_rays);
  for (size_t i = 0; i < n_rays; ++i) {
    directions_[i] = (head_to_world.linear() * ray_directions_[i]).normalized().cast<float>();
  }
  hits_.resize(n_rays);
  world.castMany(origins_, directions_, static_cast<float>(o.max_range), hits_);

  // Echo envelope: each ray returns a pulse of strength (beam weight x Lambert backscatter
  // cos^2(incidence)); a target closer than min_range is blanked but still shadows the beam.
  const double spacing = ping.range_resolution / kOversampling;
  std::fill(envelope_.begin(), envelope_.end(), 0.0);
  for (size_t i = 0; i < n_rays; ++i) {
    const RayHit& hit = hits_[i];
    if (!hit.hit() || hit.distance < o.min_range || hit.distance > o.max_range) continue;
    const double cos_incidence = std::abs(directions_[i].dot(hit.normal));
    const double strength = ray_weights_[i] * cos_incidence * cos_incidence;
    depositPulse(envelope_, spacing, hit.distance - o.min_range, o.pulse_length,
                 255.0 * o.gain * strength);
  }
  // Receiver noise, and with some probability a spurious echo (fish, bubbles, a side lobe)
  // at a random range; random numbers are drawn every ping so sequences stay aligned.
  for (double& sample : envelope_) sample += std::abs(gaussian(o.noise_level));
  const double false_draw = uniform_(rng_);
  const double false_range = uniform_(rng_) * (o.max_range - o.min_range - o.pulse_length);
  const double false_level =
      o.detection_threshold + uniform_(rng_) * (255.0 - o.detection_threshold);
  if (false_draw < o.false_return_probability) {
    const int first = static_cast<int>(false_range / spacing);
    const int count = std::max(1, static_cast<int>(std::ceil(o.pulse_length / spacing)));
    for (int k = first; k < std::min<int>(first + count, envelope_.size()); ++k) {
      envelope_[k] += false_level + 1.0;
    }
  }
  const double range_noise = gaussian(o.range_noise);

  // First return: the leading edge of the first echo above the threshold (linear
  // interpolation of the crossing between samples), as a profiler reports it.
  const double threshold = o.detection_threshold;
  const auto first_above = std::find_if(envelope_.begin(), envelope_.end(),
                                        [threshold](double v) { return v >= threshold; });
  if (first_above != envelope_.end()) {
    const int k = static_cast<int>(first_above - envelope_.begin());
    const double before = k > 0 ? envelope_[k - 1] : 0.0;
    const double fraction = (threshold - before) / std::max(envelope_[k] - before, 1e-12);
    const double edge = o.min_range + (k - 0.5 + fraction) * spacing;
    double peak = 0.0;
    for (size_t j = k; j < envelope_.size() && envelope_[j] >= threshold; ++j) {
      peak = std::max(peak, envelope_[j]);
    }
    const double range = std::clamp(edge + range_noise, o.min_range, o.max_range);
    ping.ranges.push_back(static_cast<float>(range));
    ping.intensities.push_back(static_cast<float>(std::min(1.0, peak / 255.0)));
    ping.flags |= sonar_flags::kEchoReturned;
  }

  // Reported bins: the envelope averaged over each bin, clipped to 0..255.
  ping.bins.resize(o.bins);
  for (int b = 0; b < o.bins; ++b) {
    double sum = 0.0;
    for (int s = 0; s < kOversampling; ++s) sum += envelope_[b * kOversampling + s];
    const double level = sum / kOversampling;
    if (level > 255.0) ping.flags |= sonar_flags::kSaturated;
    ping.bins[b] = static_cast<uint8_t>(std::lround(std::clamp(level, 0.0, 255.0)));
  }

  // Schedule: keep the nominal rate when the caller steps finer than the period; if it fell a
  // whole period behind, drop the missed pings instead of bursting.
  if (first_ping_ || time - next_ping_time_ >= period_ || time + 1e-9 < next_ping_time_) {
    next_ping_time_ = time + period_;
  } else {
    next_ping_time_ += period_;
  }
  first_ping_ = false;
  advanceHead();
  return ping;
}

}  // namespace auv::sim
