#include "auv/sim/world/surface_detail.h"

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>

#include "auv/sim/common/yaml_section.h"

namespace auv::sim {
namespace {

constexpr int kTilePixels = 512;
// The second layer: tiles 1.618... times larger (an irrational ratio: the layers never line up
// again) and turned by 15.6 deg: of the angles tried, the one whose second layer stays
// farthest from lining up (>= 0.14 of its tile) at every multiple of the first tile to 20 tiles.
constexpr float kSecondScale = 1.6180340f;
constexpr float kSecondCos = 0.96316257f, kSecondSin = 0.26891982f;

// Sum of value-noise octaves on lattices of 8..256 cells (6 cm down to 2 mm on a 0.5 m tile),
// each interpolated bicubically with wrap-around so the tile repeats seamlessly. Equal weights:
// the texture already holds the coarse scales; the detail must carry the fine ones, where
// feature detectors look.
cv::Mat tileableNoise(uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  cv::Mat sum = cv::Mat::zeros(kTilePixels, kTilePixels, CV_32F);
  const float weight = 1.0f;
  for (int cells = 8; cells <= kTilePixels / 2; cells *= 2) {
    cv::Mat lattice(cells, cells, CV_32F);
    for (int r = 0; r < cells; ++r) {
      for (int c = 0; c < cells; ++c) lattice.at<float>(r, c) = normal(rng);
    }
    const int pad = 2;
    cv::Mat padded;
    cv::copyMakeBorder(lattice, padded, pad, pad, pad, pad, cv::BORDER_WRAP);
    const int cell_px = kTilePixels / cells;
    cv::Mat up;
    cv::resize(padded, up, cv::Size((cells + 2 * pad) * cell_px, (cells + 2 * pad) * cell_px), 0, 0,
               cv::INTER_CUBIC);
    sum += weight * up(cv::Rect(pad * cell_px, pad * cell_px, kTilePixels, kTilePixels));
  }
  cv::Scalar mean, stddev;
  cv::meanStdDev(sum, mean, stddev);
  sum = (sum - mean[0]) / std::max(1e-6, stddev[0]);
  return sum;
}

}  // namespace

void SurfaceDetailOptions::check(const std::string& where) const {
  if (!std::isfinite(amplitude) || amplitude < 0 || amplitude > 2) {
    throw ConfigError(where + ".amplitude: expected a number in [0, 2]");
  }
  if (!std::isfinite(tile_size) || tile_size <= 0 || tile_size > 100) {
    throw ConfigError(where + ".tile_size: expected metres in (0, 100]");
  }
}

SurfaceDetail::SurfaceDetail(const SurfaceDetailOptions& options)
    : options_(options),
      tile_(tileableNoise(static_cast<uint64_t>(options.seed))),
      second_tile_(tileableNoise(static_cast<uint64_t>(options.seed) ^ 0x9e3779b97f4a7c15ULL)),
      inverse_tile_size_(static_cast<float>(1.0 / options.tile_size)),
      amplitude_(static_cast<float>(options.amplitude)),
      mean_correction_(static_cast<float>(-0.5 * options.amplitude * options.amplitude)) {
  options.check("surface_detail");
}

float SurfaceDetail::sample(const cv::Mat& tile, float u, float v) {
  const float x = (u - std::floor(u)) * kTilePixels;
  const float y = (v - std::floor(v)) * kTilePixels;
  const int x0 = static_cast<int>(x) % kTilePixels, y0 = static_cast<int>(y) % kTilePixels;
  const int x1 = (x0 + 1) % kTilePixels, y1 = (y0 + 1) % kTilePixels;
  const float fx = x - std::floor(x), fy = y - std::floor(y);
  const float* r0 = tile.ptr<float>(y0);
  const float* r1 = tile.ptr<float>(y1);
  return (1 - fy) * ((1 - fx) * r0[x0] + fx * r0[x1]) + fy * ((1 - fx) * r1[x0] + fx * r1[x1]);
}

float SurfaceDetail::layers(float x, float y) const {
  const float u = x * inverse_tile_size_, v = y * inverse_tile_size_;
  const float su = (kSecondCos * u - kSecondSin * v) / kSecondScale;
  const float sv = (kSecondSin * u + kSecondCos * v) / kSecondScale;
  return (sample(tile_, u, v) + sample(second_tile_, su, sv)) * 0.70710678f;  // independent
}

float SurfaceDetail::factor(const Eigen::Vector3f& p, const Eigen::Vector3f& n) const {
  // Triplanar: each axis-aligned projection weighted by how squarely the surface faces it
  // (sharpened so walls and floors each take mostly one projection).
  Eigen::Vector3f w = n.cwiseAbs().array().pow(4.0f).matrix();
  w /= std::max(1e-6f, w.sum());
  // Different offsets per plane so the three projections do not repeat each other.
  const float value = w.x() * layers(p.y() + 0.37f, p.z() + 0.11f) +
                      w.y() * layers(p.x() + 0.73f, p.z() + 0.53f) +
                      w.z() * layers(p.x() + 0.19f, p.y() + 0.91f);
  return std::exp(amplitude_ * value + mean_correction_);
}

}  // namespace auv::sim
