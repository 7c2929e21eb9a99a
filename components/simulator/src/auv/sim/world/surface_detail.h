#pragma once
// Fine surface detail below a world texture's resolution. A 100 m world's texture atlas gives
// ~2 cm per texel, but a camera 1-2 m from rock sees 2-3 mm per pixel: magnified, the texture
// is smooth blobs and feature detectors find nothing, whereas real rock has grain, pits and
// encrusting life at every scale. The detail is seeded, tileable multi-octave noise projected
// triplanarly in world coordinates (so every view of a point agrees, as structure from motion
// needs) that modulates the albedo multiplicatively around 1. Two layers of different noise,
// the second on tiles golden-ratio times larger and turned, so the sum never repeats: one
// tile alone repeated every tile_size, and on plain sand, where the detail is all there is,
// matching then found the same patch half a metre away as often as the right one.

#include <Eigen/Core>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>

namespace auv::sim {

/// Scenario key `world.surface_detail` (absent = no detail: a user's mesh looks as given).
struct SurfaceDetailOptions {
  double amplitude = 0.0;  ///< std of the log-albedo modulation; 0 = off, 0.3-0.6 = rock grain
  double tile_size = 0.5;  ///< m, world size of the first layer's tile (1 mm/texel at 512)
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
  /// One layer at tile coordinates (u, v) (repeating), bilinear.
  static float sample(const cv::Mat& tile, float u, float v);
  /// Both layers at plane coordinates (x, y) in metres: zero mean, unit std.
  float layers(float x, float y) const;

  SurfaceDetailOptions options_;
  cv::Mat tile_, second_tile_;  // CV_32F, zero mean, unit std, tileable; independent noise
  float inverse_tile_size_ = 2.0f;
  float amplitude_ = 0.0f;
  float mean_correction_ = 0.0f;  // -amplitude^2 / 2: keeps the mean factor at 1
};

}  // namespace auv::sim
