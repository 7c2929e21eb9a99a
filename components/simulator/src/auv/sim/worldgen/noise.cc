#include "auv/sim/worldgen/noise.h"

#include <algorithm>
#include <cmath>

namespace auv::sim::worldgen {
namespace {

// Lattice hashing: per-axis products, combined per corner and mixed once. No period (unlike
// Perlin's 256-entry permutation table, which would repeat fine octaves every few metres).
constexpr uint32_t kPrimeX = 0x8da6b343u, kPrimeY = 0xd8163841u, kPrimeZ = 0xcb1ab31fu;

inline uint32_t mixHash(uint32_t h) {
  h *= 0x7feb352du;
  h ^= h >> 15;
  h *= 0x846ca68bu;
  return h >> 28;  // top 4 bits: one of 16 gradients
}

inline int32_t fastFloor(float x) {
  const int32_t i = static_cast<int32_t>(x);
  return x < static_cast<float>(i) ? i - 1 : i;
}

// Perlin's 12 edge gradients, 4 repeated to make 16 (a table: no unpredictable branches).
constexpr float kGradients[16][3] = {
    {1, 1, 0}, {-1, 1, 0}, {1, -1, 0}, {-1, -1, 0}, {1, 0, 1}, {-1, 0, 1}, {1, 0, -1}, {-1, 0, -1},
    {0, 1, 1}, {0, -1, 1}, {0, 1, -1}, {0, -1, -1}, {1, 1, 0}, {0, -1, 1}, {-1, 1, 0}, {0, -1, -1}};

inline float gradientDot(uint32_t hash, float x, float y, float z) {
  const float* g = kGradients[hash];
  return g[0] * x + g[1] * y + g[2] * z;
}

inline float fade(float t) { return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f); }
inline float lerp(float a, float b, float t) { return a + t * (b - a); }

// Rotates the domain between octaves so lattice-aligned artefacts of one octave do not line up
// with the next (an orthonormal matrix, about 37 degrees about a skew axis).
inline Eigen::Vector3f rotateOctave(const Eigen::Vector3f& p) {
  return {0.80f * p.x() + 0.36f * p.y() - 0.48f * p.z(),
          -0.48f * p.x() + 0.80f * p.y() - 0.36f * p.z(),
          0.36f * p.x() + 0.48f * p.y() + 0.80f * p.z()};
}

int octavesToKeep(float wavelength, int octaves, float min_wavelength) {
  int kept = 1;
  float w = wavelength * 0.5f;
  while (kept < octaves && w >= min_wavelength) {
    ++kept;
    w *= 0.5f;
  }
  return kept;
}

}  // namespace

GradientNoise::GradientNoise(uint64_t seed)
    : seed_(static_cast<uint32_t>(seed ^ (seed >> 32)) * 0x9e3779b9u + 0x632be5abu) {}

float GradientNoise::noise(const Eigen::Vector3f& p) const {
  const int32_t ix = fastFloor(p.x()), iy = fastFloor(p.y()), iz = fastFloor(p.z());
  const float x = p.x() - static_cast<float>(ix), y = p.y() - static_cast<float>(iy),
              z = p.z() - static_cast<float>(iz);
  const float u = fade(x), v = fade(y), w = fade(z);
  const uint32_t hx0 = static_cast<uint32_t>(ix) * kPrimeX, hx1 = hx0 + kPrimeX;
  const uint32_t hy0 = static_cast<uint32_t>(iy) * kPrimeY, hy1 = hy0 + kPrimeY;
  const uint32_t hz = static_cast<uint32_t>(iz) * kPrimeZ;
  const uint32_t hz0 = hz ^ seed_, hz1 = (hz + kPrimeZ) ^ seed_;
  const float n000 = gradientDot(mixHash(hx0 ^ hy0 ^ hz0), x, y, z);
  const float n100 = gradientDot(mixHash(hx1 ^ hy0 ^ hz0), x - 1, y, z);
  const float n010 = gradientDot(mixHash(hx0 ^ hy1 ^ hz0), x, y - 1, z);
  const float n110 = gradientDot(mixHash(hx1 ^ hy1 ^ hz0), x - 1, y - 1, z);
  const float n001 = gradientDot(mixHash(hx0 ^ hy0 ^ hz1), x, y, z - 1);
  const float n101 = gradientDot(mixHash(hx1 ^ hy0 ^ hz1), x - 1, y, z - 1);
  const float n011 = gradientDot(mixHash(hx0 ^ hy1 ^ hz1), x, y - 1, z - 1);
  const float n111 = gradientDot(mixHash(hx1 ^ hy1 ^ hz1), x - 1, y - 1, z - 1);
  const float nx00 = lerp(n000, n100, u), nx10 = lerp(n010, n110, u);
  const float nx01 = lerp(n001, n101, u), nx11 = lerp(n011, n111, u);
  // Improved noise peaks near +-1.04; scale so the usual range is about [-1, 1].
  return 0.96f * lerp(lerp(nx00, nx10, v), lerp(nx01, nx11, v), w);
}

float GradientNoise::fbm(const Eigen::Vector3f& p, float wavelength, int octaves, float gain,
                         float min_wavelength) const {
  const int kept = octavesToKeep(wavelength, octaves, min_wavelength);
  Eigen::Vector3f q = p / wavelength;
  float sum = 0.0f, amplitude = 1.0f, norm = 0.0f;
  for (int i = 0; i < kept; ++i) {
    sum += amplitude * noise(q);
    norm += amplitude;
    amplitude *= gain;
    q = rotateOctave(q) * 2.0f + Eigen::Vector3f(17.3f, -5.1f, 9.7f);
  }
  // Sums of independent octaves rarely reach the sum of amplitudes; 0.75 keeps the usual range
  // near [-1, 1] whatever the octave count.
  return sum / (norm * 0.75f);
}

float GradientNoise::ridged(const Eigen::Vector3f& p, float wavelength, int octaves, float gain,
                            float min_wavelength) const {
  const int kept = octavesToKeep(wavelength, octaves, min_wavelength);
  Eigen::Vector3f q = p / wavelength + Eigen::Vector3f(-31.7f, 11.9f, 4.3f);
  float sum = 0.0f, amplitude = 1.0f, norm = 0.0f;
  for (int i = 0; i < kept; ++i) {
    const float crease = 1.0f - std::abs(noise(q));
    sum += amplitude * crease * crease;
    norm += amplitude;
    amplitude *= gain;
    q = rotateOctave(q) * 2.0f + Eigen::Vector3f(17.3f, -5.1f, 9.7f);
  }
  return sum / norm;
}

float noise1d(const GradientNoise& noise, float x, float wavelength, int octaves) {
  return noise.fbm(Eigen::Vector3f(x, 0.37f, -0.71f), wavelength, octaves);
}

}  // namespace auv::sim::worldgen
