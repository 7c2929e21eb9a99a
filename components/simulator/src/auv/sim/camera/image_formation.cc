#include "auv/sim/camera/image_formation.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "auv/sim/camera/camera_model.h"

namespace auv::sim {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr int kSrgbTableSize = 65536;

// Linear [0, 1] -> sRGB [0, 1], tabulated finely enough (2^16 steps) that the table's error
// stays far below one 8-bit step even in the steep dark end.
const std::vector<float>& srgbEncodeTable() {
  static const std::vector<float> table = [] {
    std::vector<float> t(kSrgbTableSize + 1);
    for (int i = 0; i <= kSrgbTableSize; ++i) {
      t[i] = linearToSrgb(static_cast<float>(i) / kSrgbTableSize);
    }
    return t;
  }();
  return table;
}

float encodeSrgb(float linear) {
  const float clamped = std::clamp(linear, 0.0f, 1.0f);
  return srgbEncodeTable()[static_cast<int>(clamped * kSrgbTableSize + 0.5f)];
}

}  // namespace

void IlluminationOptions::check(const std::string& where) const {
  for (int c = 0; c < 3; ++c) {
    if (!std::isfinite(surface_irradiance[c]) || surface_irradiance[c] < 0 ||
        surface_irradiance[c] > 100) {
      throw ConfigError(where + ".surface_irradiance: expected [0, 100] per channel (linear)");
    }
  }
  if (!(sun_zenith_deg >= 0 && sun_zenith_deg <= 90)) {
    throw ConfigError(where + ".sun_zenith_deg: expected [0, 90] deg");
  }
  if (!std::isfinite(sun_azimuth_deg))
    throw ConfigError(where + ".sun_azimuth_deg: must be finite");
  if (!(ambient >= 0 && ambient <= 1)) throw ConfigError(where + ".ambient: expected [0, 1]");
  if (!(diffuse_attenuation_ratio > 0 && diffuse_attenuation_ratio <= 1)) {
    throw ConfigError(where + ".diffuse_attenuation_ratio: expected (0, 1]");
  }
  if (!(veiling_gain_up >= 0 && veiling_gain_up <= 10)) {
    throw ConfigError(where + ".veiling_gain_up: expected [0, 10]");
  }
}

IlluminationOptions IlluminationOptions::fromYaml(const YamlSection& s) {
  s.rejectUnknownKeys({"surface_irradiance", "sun_zenith_deg", "sun_azimuth_deg", "ambient",
                       "diffuse_attenuation_ratio", "veiling_gain_up"});
  IlluminationOptions o;
  s.read("surface_irradiance", o.surface_irradiance, 0.0, 100.0);
  s.read("sun_zenith_deg", o.sun_zenith_deg, 0.0, 90.0);
  s.read("sun_azimuth_deg", o.sun_azimuth_deg, -360.0, 360.0);
  s.read("ambient", o.ambient, 0.0, 1.0);
  s.read("diffuse_attenuation_ratio", o.diffuse_attenuation_ratio, 0.01, 1.0);
  s.read("veiling_gain_up", o.veiling_gain_up, 0.0, 10.0);
  o.check(s.file() + ": " + (s.path().empty() ? "lighting" : s.path()));
  return o;
}

IlluminationOptions IlluminationOptions::fromScenario(const Scenario& scenario) {
  if (!scenario.root.has("lighting")) return IlluminationOptions{};
  return fromYaml(scenario.root.child("lighting"));
}

ImageFormation::ImageFormation(const WaterOptics& water, const IlluminationOptions& illumination,
                               std::vector<SpotLight> lights, double exposure_reference)
    : water_(water),
      illumination_(illumination),
      lights_(std::move(lights)),
      exposure_reference_(exposure_reference) {
  water_.check("water");
  illumination_.check();
  if (!(exposure_reference_ > 0) || !std::isfinite(exposure_reference_)) {
    throw std::invalid_argument("ImageFormation: exposure reference must be > 0");
  }
  attenuation_ = water_.attenuation.cast<float>().array();
  backscatter_ = water_.backscatter.cast<float>().array();
  veiling_ = water_.veiling_light.cast<float>().array();
  sun_ = illumination_.surface_irradiance.cast<float>().array();
  downwelling_ = attenuation_ * static_cast<float>(illumination_.diffuse_attenuation_ratio);
  const double zenith = illumination_.sun_zenith_deg * kDeg;
  const double azimuth = illumination_.sun_azimuth_deg * kDeg;
  towards_sun_ = Eigen::Vector3d(std::sin(zenith) * std::cos(azimuth),
                                 std::sin(zenith) * std::sin(azimuth), -std::cos(zenith))
                     .cast<float>();
  for (SpotLight& light : lights_) {
    light.direction.normalize();
    const double half = 0.5 * light.beam_deg * kDeg, soft = 5.0 * kDeg;
    cos_inner_.push_back(static_cast<float>(std::cos(std::max(0.0, half - soft))));
    cos_outer_.push_back(static_cast<float>(std::cos(std::min(M_PI, half + soft))));
  }
}

Eigen::Vector3f ImageFormation::irradiance(const Eigen::Vector3f& point,
                                           const Eigen::Vector3f& normal) const {
  const float depth = std::max(0.0f, point.z());
  const float cosine = std::max(0.0f, normal.dot(towards_sun_));
  const float ambient = static_cast<float>(illumination_.ambient);
  Eigen::Array3f e = sun_ * (-downwelling_ * depth).exp() * (ambient + (1.0f - ambient) * cosine);
  for (size_t i = 0; i < lights_.size(); ++i) {
    const SpotLight& light = lights_[i];
    Eigen::Vector3f to_light = light.position - point;
    const float r = std::max(0.05f, to_light.norm());
    to_light /= r;
    const float lambert = normal.dot(to_light);
    if (lambert <= 0) continue;
    const float cos_angle = -to_light.dot(light.direction);
    const float cone =
        std::clamp((cos_angle - cos_outer_[i]) / (cos_inner_[i] - cos_outer_[i]), 0.0f, 1.0f);
    if (cone <= 0) continue;
    e += light.intensity * cone * lambert / (r * r) * (-attenuation_ * r).exp();
  }
  return e.matrix();
}

Eigen::Vector3f ImageFormation::waterRadiance(const Eigen::Vector3f& direction) const {
  const float gain =
      1.0f + static_cast<float>(illumination_.veiling_gain_up) * std::max(0.0f, -direction.z());
  return (veiling_ * gain).matrix();
}

Eigen::Vector3f ImageFormation::surfaceRadiance(const Eigen::Vector3f& direction, float distance,
                                                const Eigen::Vector3f& point,
                                                const Eigen::Vector3f& normal,
                                                const Eigen::Vector3f& albedo) const {
  const Eigen::Array3f direct = albedo.array() * irradiance(point, normal).array() *
                                (-attenuation_ * distance).exp() /
                                static_cast<float>(exposure_reference_);
  const Eigen::Array3f scattered =
      waterRadiance(direction).array() * (1.0f - (-backscatter_ * distance).exp());
  return (direct + scattered).matrix();
}

Eigen::Vector3f ImageFormation::radiance(const Eigen::Vector3f& direction, const RayHit& hit,
                                         const RayCaster& caster) const {
  if (!hit.hit()) return waterRadiance(direction);
  return surfaceRadiance(direction, hit.distance, caster.pointAt(hit), hit.normal,
                         caster.colorAt(hit));
}

double meteredIrradiance(const WaterOptics& water, const IlluminationOptions& illumination,
                         const std::vector<SpotLight>& lights, double camera_depth) {
  constexpr double kMeteringDistance = 1.5;  // m, a typical subject distance
  const double green = water.attenuation[1];
  const double zenith = illumination.sun_zenith_deg * M_PI / 180.0;
  double level =
      illumination.surface_irradiance[1] *
      std::exp(-illumination.diffuse_attenuation_ratio * green * std::max(0.0, camera_depth)) *
      (illumination.ambient + (1.0 - illumination.ambient) * std::cos(zenith));
  for (const SpotLight& light : lights) {
    level += light.intensity * std::exp(-green * kMeteringDistance) /
             (kMeteringDistance * kMeteringDistance);
  }
  return std::max(level, 1e-4);
}

ImageFormation cameraImageFormation(const CameraOptions& camera, const WaterOptics& water,
                                    const IlluminationOptions& illumination,
                                    std::vector<SpotLight> lights,
                                    const Eigen::Vector3d& camera_position) {
  const double reference = camera.auto_exposure
                               ? meteredIrradiance(water, illumination, lights, camera_position.z())
                               : 1.0;
  return ImageFormation(water, illumination, std::move(lights), reference);
}

uint64_t frameSeed(uint64_t camera_seed, uint64_t frame) {
  uint64_t z = camera_seed * 0x9e3779b97f4a7c15ull + frame + 0x632be59bd9b4e019ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

cv::Mat developImage(const cv::Mat& radiance, const cv::Mat& cos_off_axis,
                     const CameraOptions& camera, uint64_t noise_seed) {
  CV_Assert(radiance.type() == CV_32FC3 && cos_off_axis.type() == CV_32F &&
            radiance.size() == cos_off_axis.size());
  const float vignetting = static_cast<float>(camera.vignetting);
  const float exposure = static_cast<float>(camera.exposure);
  const float sigma = static_cast<float>(camera.noise_sigma);
  std::mt19937_64 rng(noise_seed);
  std::normal_distribution<float> noise(0.0f, 1.0f);
  cv::Mat out(radiance.size(), CV_8UC3);
  for (int row = 0; row < radiance.rows; ++row) {
    const cv::Vec3f* in = radiance.ptr<cv::Vec3f>(row);
    const float* cosine = cos_off_axis.ptr<float>(row);
    cv::Vec3b* bgr = out.ptr<cv::Vec3b>(row);
    for (int col = 0; col < radiance.cols; ++col) {
      const float c2 = cosine[col] * cosine[col];
      const float gain = exposure * ((1.0f - vignetting) + vignetting * c2 * c2);
      for (int c = 0; c < 3; ++c) {
        float value = encodeSrgb(in[col][c] * gain);
        if (sigma > 0) value += sigma * noise(rng);
        bgr[col][2 - c] = cv::saturate_cast<uchar>(value * 255.0f);
      }
    }
  }
  return out;
}

}  // namespace auv::sim
