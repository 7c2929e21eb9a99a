#pragma once
// Underwater image formation (Akkaynak & Treibitz, "A revised underwater image formation
// model", CVPR 2018, simplified to one attenuation and one backscatter coefficient per
// channel, as WaterOptics holds them). For a camera ray that hits a surface of linear albedo
// rho at range d, per channel c:
//
//   I_c = rho_c * E_c * exp(-attenuation_c * d) + B_c * g(ray) * (1 - exp(-backscatter_c * d))
//
// * E_c, the irradiance at the hit point (white = 1):
//     daylight:  S_c * exp(-K_c * depth) * (ambient + (1 - ambient) * max(0, n . s))
//                (downwelling light attenuated over the water column above the point; s the
//                unit direction towards the refracted sun, n the surface normal). Diffuse
//                downwelling light is attenuated less than a beam: K_c = diffuse_attenuation_ratio
//                * attenuation_c (K_d ~ 0.3-0.5 c in coastal water; 1 = the beam coefficient), plus
//     lights:    P * cone(angle) * exp(-attenuation_c * r) / r^2 * max(0, n . l)
//                for every artificial light (inverse square, attenuated over its path r,
//                soft-edged beam cone; no shadows, no light-induced backscatter).
// * B_c is the veiling light (WaterOptics::veiling_light); g(ray) = 1 + veiling_gain_up *
//   max(0, -ray_z) makes the water slightly brighter towards the surface.
// * A ray that hits nothing sees B_c * g(ray).
// Units and exposure: a white Lambertian surface under irradiance 1 has radiance 1 (the 1/pi
// is folded into S and P), and E is divided by the exposure reference: the irradiance the
// camera's auto exposure meters (meteredIrradiance: the green daylight at the camera's depth
// plus its lights' light on a white surface 1.5 m ahead), or 1 without auto exposure. The
// veiling light, which in the water scales with the same ambient light, thus reads as
// WaterOptics::veiling_light at any depth, while scenes deeper or shallower than the camera
// darken or brighten, and red fades with depth as it does in the water.
//
// The sensor then applies vignetting (blend towards cos^4 of the off-axis angle), the
// exposure gain, sRGB encoding, Gaussian noise (seeded, in the encoded domain, like the
// encoder's input) and quantisation to 8-bit BGR (developImage). Red is lost first because the
// water's red attenuation is several times green's and blue's.

#include <Eigen/Core>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "auv/sim/common/yaml_section.h"
#include "auv/sim/raycast/ray_caster.h"
#include "auv/sim/world/scenario.h"

namespace auv::sim {

struct CameraOptions;

/// Daylight reaching the scene; scenario section `lighting` (optional).
struct IlluminationOptions {
  /// Linear RGB irradiance just below the surface (white = 1).
  Eigen::Vector3d surface_irradiance{1.0, 1.0, 1.0};
  double sun_zenith_deg = 20.0;  ///< deg from the vertical, underwater (refracted, <= ~48)
  double sun_azimuth_deg = 0.0;  ///< deg, direction the light comes from, 0 = north, 90 = east
  /// Fraction of the downwelling light that is diffuse (0..1). A few metres down in coastal
  /// water the light field is mostly diffuse: walls facing away from the sun still get half.
  double ambient = 0.5;
  /// Downwelling (diffuse) attenuation over depth as a fraction of the beam attenuation (0..1].
  double diffuse_attenuation_ratio = 0.4;
  double veiling_gain_up = 0.3;  ///< extra veiling light looking straight up (fraction)

  void check(const std::string& where = "lighting") const;
  /// Keys: surface_irradiance ([r, g, b]), sun_zenith_deg, sun_azimuth_deg, ambient,
  /// diffuse_attenuation_ratio, veiling_gain_up; unknown keys rejected.
  static IlluminationOptions fromYaml(const YamlSection& section);
  /// The scenario's `lighting` section, or the defaults when it has none.
  static IlluminationOptions fromScenario(const Scenario& scenario);
};

/// An artificial light on the vehicle, in the world frame.
struct SpotLight {
  Eigen::Vector3f position{0, 0, 0};   ///< m
  Eigen::Vector3f direction{1, 0, 0};  ///< unit, beam axis
  float intensity = 1.0f;              ///< irradiance at 1 m on the axis before attenuation
  float beam_deg = 100.0f;             ///< deg, full cone angle (+10 deg soft edge)
};

/// The physical part: radiance reaching the camera along a ray. Immutable, thread-safe.
class ImageFormation {
 public:
  /// `exposure_reference` (> 0): the irradiance that reads as full scale (see the file comment).
  ImageFormation(const WaterOptics& water, const IlluminationOptions& illumination,
                 std::vector<SpotLight> lights = {}, double exposure_reference = 1.0);

  /// Irradiance (linear RGB, absolute: surface daylight = 1) on a surface at `point` (world
  /// NED) with unit `normal`.
  Eigen::Vector3f irradiance(const Eigen::Vector3f& point, const Eigen::Vector3f& normal) const;
  /// Radiance along a unit ray (world) hitting a surface of linear `albedo` at `distance`.
  Eigen::Vector3f surfaceRadiance(const Eigen::Vector3f& direction, float distance,
                                  const Eigen::Vector3f& point, const Eigen::Vector3f& normal,
                                  const Eigen::Vector3f& albedo) const;
  /// Radiance along a unit ray (world) that hits nothing: the veiling light.
  Eigen::Vector3f waterRadiance(const Eigen::Vector3f& direction) const;
  /// Either of the above for a ray cast result (albedo and point from the caster).
  Eigen::Vector3f radiance(const Eigen::Vector3f& direction, const RayHit& hit,
                           const RayCaster& caster) const;

  const WaterOptics& water() const { return water_; }
  const IlluminationOptions& illumination() const { return illumination_; }
  const std::vector<SpotLight>& lights() const { return lights_; }
  double exposureReference() const { return exposure_reference_; }

 private:
  WaterOptics water_;
  IlluminationOptions illumination_;
  std::vector<SpotLight> lights_;
  double exposure_reference_ = 1.0;
  Eigen::Array3f attenuation_, backscatter_, veiling_, sun_, downwelling_;
  Eigen::Vector3f towards_sun_;
  std::vector<float> cos_inner_, cos_outer_;
};

/// What auto exposure meters for a camera at `camera_depth` (m): the green daylight there (on a
/// white surface facing up) plus
/// each light's green irradiance on a white surface 1.5 m along its beam; at least 1e-4.
double meteredIrradiance(const WaterOptics& water, const IlluminationOptions& illumination,
                         const std::vector<SpotLight>& lights, double camera_depth);

/// The image formation a camera at `camera_to_world` sees: with its auto exposure (when on)
/// metering the light at its depth.
ImageFormation cameraImageFormation(const CameraOptions& camera, const WaterOptics& water,
                                    const IlluminationOptions& illumination,
                                    std::vector<SpotLight> lights,
                                    const Eigen::Vector3d& camera_position);

/// The sensor: vignetting (from `cos_off_axis`, CV_32F per pixel), exposure gain, sRGB
/// encoding, noise of std `noise_sigma` (full scale = 1) seeded by `noise_seed`, 8-bit
/// quantisation. `radiance` is CV_32FC3 linear RGB; returns CV_8UC3 BGR.
cv::Mat developImage(const cv::Mat& radiance, const cv::Mat& cos_off_axis,
                     const CameraOptions& camera, uint64_t noise_seed);

/// A seed for frame `frame` of a camera whose own seed is `camera_seed` (SplitMix64), so each
/// frame's noise is reproducible whatever the order frames are rendered in.
uint64_t frameSeed(uint64_t camera_seed, uint64_t frame);

}  // namespace auv::sim
