#pragma once
// Fine surface detail below a world texture's resolution. A 100 m world's texture atlas gives
// ~2 cm per texel, but a camera 1-2 m from rock sees 2-3 mm per pixel: magnified, the texture
// is smooth blobs and feature detectors find nothing, whereas real rock has grain, pits and
// encrusting life at every scale. The detail is a seeded, tileable multi-octave noise image
// projected triplanarly in world coordinates (so every view of a point agrees, as structure
// from motion needs) that modulates the albedo multiplicatively around 1.

#include <Eigen/Core>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>

namespace auv::sim {

/// Scenario key `world.surface_detail` (absent = no detail: a user's mesh looks as given).
struct SurfaceDetailOptions {
  double amplitude = 0.0;  ///< std of the log-albedo modulation; 0 = off, 0.3-0.6 = rock grain
  double tile_size = 0.5;  ///< m, world size of one tile of the detail image (1 mm/texel at 512)
  int64_t seed = 1;        ///< the noise pattern

  bool enabled() const { return amplitude > 0; }
  /// Throws ConfigError naming `where`.amplitude / .tile_size.
  void check(const std::string& where) const;
};

class SurfaceDetail {
 public:
  explicit SurfaceDetail(const SurfaceDetailOptions& options);
  /// Albedo factor at world point `p` with unit normal `n`; log-normal with mean 1.
  float factor(const Eigen::Vector3f& p, const Eigen::Vector3f& n) const;
  const SurfaceDetailOptions& options() const { return options_; }

 private:
  float sample(float u, float v) const;  // tile coordinates (repeat), bilinear

  SurfaceDetailOptions options_;
  cv::Mat tile_;  // CV_32F, zero mean, unit std, tileable
  float inverse_tile_size_ = 2.0f;
  float amplitude_ = 0.0f;
  float mean_correction_ = 0.0f;  // -amplitude^2 / 2: keeps the mean factor at 1
};

}  // namespace auv::sim
