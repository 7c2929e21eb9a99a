#pragma once
// Seeded 3D gradient noise (Perlin's improved noise on a hashed lattice, so it never repeats
// within the int range) and its fractal sums. The procedural worlds displace geometry and
// colour solid textures with it; the same seed always gives the same values.

#include <Eigen/Core>
#include <cstdint>

namespace auv::sim::worldgen {

class GradientNoise {
 public:
  explicit GradientNoise(uint64_t seed);

  /// Noise in about [-1, 1] with features about one lattice unit wide; 0 at lattice points.
  float noise(const Eigen::Vector3f& p) const;

  /// Fractal Brownian motion: `octaves` octaves of noise, the first with wavelength
  /// `wavelength` (units of p), each next one half as long and `gain` times as strong, summed
  /// and normalised to about [-1, 1]. Octaves shorter than `min_wavelength` are skipped (they
  /// would alias when sampled at that spacing); at least one octave is always kept.
  float fbm(const Eigen::Vector3f& p, float wavelength, int octaves, float gain = 0.5f,
            float min_wavelength = 0.0f) const;

  /// Ridged fractal in [0, 1]: 1 - |noise| per octave, squared, so it peaks in thin creases
  /// (crags on rock, cracks in a texture). Same parameters as fbm().
  float ridged(const Eigen::Vector3f& p, float wavelength, int octaves, float gain = 0.5f,
               float min_wavelength = 0.0f) const;

  uint32_t seed() const { return seed_; }

 private:
  uint32_t seed_;
};

/// Smooth 1D noise in about [-1, 1] along a line (e.g. a wall's width along a canyon).
float noise1d(const GradientNoise& noise, float x, float wavelength, int octaves);

/// Hermite step 0 -> 1 between edge0 and edge1 (GLSL smoothstep).
inline float smoothStep(float edge0, float edge1, float x) {
  float t = (x - edge0) / (edge1 - edge0);
  t = t < 0.0f ? 0.0f : (t > 1.0f ? 1.0f : t);
  return t * t * (3.0f - 2.0f * t);
}

}  // namespace auv::sim::worldgen
