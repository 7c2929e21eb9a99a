#pragma once
// Range-aware colour restoration (Sea-thru: Akkaynak & Treibitz, "Sea-thru: A Method for Removing
// Water From Underwater Images", CVPR 2019, after their revised image formation model, CVPR
// 2018). Per channel c, for a pixel of linear colour I_c seeing a surface at range z:
//
//   I_c = V(pixel) (J_c exp(-beta_c z) + B_c(z)),
//   B_c(z) = Binf_c (1 - exp(-b_c z)) + J'_c exp(-d'_c z)
//
// J the colour the surface would have without water, V the lens vignetting (1 - v (1 - cos^4 of
// the off-axis angle): it darkens the veil as much as the scene), beta the direct-signal
// attenuation, B the backscatter (Sea-thru's form: the second term absorbs the residual direct
// signal of the darkest pixels it is fitted to). Everything is estimated blind from image/range
// pairs: the backscatter and v from the darkest pixels per range bin, the attenuation from the
// same surface points seen at different ranges.
// Channels are in R, G, B order throughout this file; images are OpenCV BGR.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace auv::recon::color {

/// The estimated water of one survey (ranges in the units of the range maps: the model's).
struct WaterModel {
  Eigen::Array3d backscatter_infinity = Eigen::Array3d::Zero();     ///< Binf, linear [0, 1]
  Eigen::Array3d backscatter_coefficient = Eigen::Array3d::Zero();  ///< b, 1/unit
  Eigen::Array3d residual_signal = Eigen::Array3d::Zero();          ///< J', linear
  Eigen::Array3d residual_decay = Eigen::Array3d::Zero();           ///< d', 1/unit
  Eigen::Array3d attenuation = Eigen::Array3d::Zero();              ///< beta_D, 1/unit
  double vignetting = 0;                                            ///< v: 0 none, 1 pure cos^4
  /// Per-channel gains applied to the restored colour (white balance), 1 = none.
  Eigen::Array3d white_balance = Eigen::Array3d::Ones();
  /// The light on the scene as a log-linear function of position (downwelling daylight fades
  /// with the depth below the surface): E_c(X) = exp(gradient.row(c) . (X - origin)); rows
  /// r, g, b in the model's frame (1/unit); zero = uniform light. origin: the cameras' mean
  /// centre (auto exposure meters the light where the camera is).
  Eigen::Matrix3d illuminant_gradient = Eigen::Matrix3d::Zero();
  Eigen::Vector3d illuminant_origin = Eigen::Vector3d::Zero();

  /// E(X) per channel.
  Eigen::Array3d illuminant(const Eigen::Vector3d& position) const;

  /// B(z) per channel.
  Eigen::Array3d backscatter(double range) const;
};

/// Fitting and restoration settings (the stage binds them to flags).
struct WaterFitOptions {
  int range_bins = 10;           ///< Sea-thru's range bins for the dark pixels
  double dark_fraction = 0.01;   ///< darkest fraction of each bin (by R+G+B)
  double min_signal = 2e-3;      ///< linear direct signal below: not used for attenuation
  int min_views = 2;             ///< views a surface point needs for the attenuation fit
  double min_range_ratio = 1.1;  ///< farthest / nearest view of a point at least
  double max_attenuation = 10;   ///< 1/unit, bound of beta and b
  bool estimate_vignetting = true;
  double loss_scale = 0.1;  ///< Cauchy scale of the attenuation residuals (log units)
  /// Refine beta, B_inf and b together on every observation in linear light (the far, veiled
  /// ones included), from the separate fits.
  bool refine_jointly = true;
  double joint_loss_scale = 0.01;            ///< Huber scale of the joint refinement (linear)
  std::string white_balance = "grey_world";  ///< grey_world or none
  /// uniform: one light for the whole scene; gradient: log-linear in position (WaterModel).
  std::string illuminant = "gradient";
  double max_gain = 20;  ///< largest exp(beta z) / V applied (noise amplification cap)

  void check() const;
};

/// A pixel for the backscatter fit.
struct RangeSample {
  float range = 0;
  Eigen::Array3f rgb;  ///< linear
  float cos4 = 1;      ///< cos^4 of the pixel's off-axis angle
};

/// One view of one surface point for the attenuation fit.
struct PointObservation {
  int32_t point = 0;
  float range = 0;
  float cos4 = 1;      ///< cos^4 of the pixel's off-axis angle
  Eigen::Array3f rgb;  ///< linear
};

struct BackscatterFitStats {
  size_t samples = 0, dark_samples = 0;
  Eigen::Array3d rms = Eigen::Array3d::Zero();  ///< of the fit over the dark samples
};

/// Fits Binf, b, J', d' per channel and v (when estimate_vignetting; else model.vignetting is
/// kept) to the darkest `dark_fraction` of the samples of each range bin, I = V B(z) (Ceres,
/// bounded, several starts). Throws std::invalid_argument when there are too few samples (< 20
/// dark ones).
BackscatterFitStats fitBackscatter(const std::vector<RangeSample>& samples,
                                   const WaterFitOptions& options, WaterModel& model);

/// A surface point's colour without water, as the attenuation fit found it.
struct PointColor {
  int32_t point = 0;
  Eigen::Array3d log_j = Eigen::Array3d::Zero();
  Eigen::Array3i observations = Eigen::Array3i::Zero();  ///< per channel, 0: log_j unknown
};

struct AttenuationFitStats {
  size_t observations = 0, points = 0;
  Eigen::Array3d rms = Eigen::Array3d::Zero();  ///< log residual after the fit
  std::vector<PointColor> colors;               ///< per point used
};

/// Fits the illuminant gradient per channel: log J_p,c = a_c + g_c . (X_p - origin) over the
/// points (Ceres, Cauchy loss of scale `loss_scale`): the light's trend across the scene,
/// assuming the albedo has none (a grey world in 3D). Sets model.illuminant_gradient and
/// illuminant_origin. Throws std::invalid_argument with fewer than 10 points per channel.
void fitIlluminantGradient(const std::vector<PointColor>& colors,
                           const std::vector<Eigen::Vector3d>& positions,
                           const Eigen::Vector3d& origin, const WaterFitOptions& options,
                           WaterModel& model);

/// Fits beta per channel from the observations, vignetting and backscatter removed with
/// `model`'s: log(I / V - B(z)) = log J_p - beta z, one log J_p per point and channel (Ceres,
/// Schur elimination of the points, Cauchy loss). Throws std::invalid_argument when fewer than
/// 10 points qualify.
AttenuationFitStats fitAttenuation(const std::vector<PointObservation>& observations,
                                   const WaterFitOptions& options, WaterModel& model);

/// Linear [0, 1] float image (CV_32FC3, BGR) of an 8-bit BGR sRGB image.
cv::Mat linearFromSrgb(const cv::Mat& bgr8);
/// 8-bit BGR sRGB image of a linear BGR float image (clipped to [0, 1]).
cv::Mat srgbFromLinear(const cv::Mat& linear);

/// cos^4 of the off-axis angle of every pixel of a pinhole camera (CV_32F).
cv::Mat cos4Map(cv::Size size, double fx, double fy, double cx, double cy);

/// Restores an 8-bit BGR image whose pixels see ranges `range` (CV_32F, same size; <= 0 or
/// non-finite: no range, the image's farthest range used) with camera `cos4` (CV_32F, same
/// size, or empty: no vignetting), divided by `illuminant` (CV_32FC3 BGR E(X) per pixel, or
/// empty: 1). Throws std::invalid_argument naming the sizes when they differ. Returns 8-bit BGR
/// sRGB.
cv::Mat restoreImage(const cv::Mat& bgr8, const cv::Mat& range, const cv::Mat& cos4,
                     const WaterModel& model, const WaterFitOptions& options,
                     const cv::Mat& illuminant = cv::Mat());

/// Rec. 709 luminance of a linear (r, g, b) colour.
inline double luminance(const Eigen::Array3d& rgb) {
  return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
}

/// Linear restored colour (before white balance) of one pixel.
Eigen::Array3d restoreLinear(const Eigen::Array3d& rgb, double range, double cos4,
                             const WaterModel& model, double max_gain);

/// restored/water.yaml (color/README.md); writeWaterModel writes through a temporary file.
void writeWaterModel(const std::filesystem::path& file, const WaterModel& model,
                     const std::string& comment);
/// Throws std::runtime_error naming the file and key.
WaterModel readWaterModel(const std::filesystem::path& file);

}  // namespace auv::recon::color
