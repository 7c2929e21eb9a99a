#include "auv/recon/change/synthetic_site.h"

#include <cmath>
#include <random>

#include "auv/recon/scene/ply.h"

namespace auv::recon::change {

bool onSyntheticBlock(double x, double y) { return x > 2.0 && x < 5.0 && y > 1.0 && y < 4.0; }
bool onSyntheticGrowth(double x, double y) { return x > -6.0 && x < -2.0 && y > -6.0 && y < -2.0; }
bool onSyntheticBleaching(double x, double y) { return x > -6.0 && x < -2.0 && y > 3.0 && y < 7.0; }

namespace {

/// Sand and rock in bands, bleached white where the changed epoch says; the changed epoch's
/// light is warmer and brighter.
Eigen::Matrix<uint8_t, 3, 1> syntheticColour(double x, double y, bool changed, std::mt19937& rng) {
  std::normal_distribution<double> noise(0.0, 0.01);
  Eigen::Vector3d c(0.45 + 0.15 * std::sin(0.9 * x), 0.42 + 0.12 * std::cos(0.7 * y), 0.30);
  if (changed && onSyntheticBleaching(x, y)) c = Eigen::Vector3d(0.85, 0.85, 0.80);
  if (changed) c = Eigen::Vector3d(1.15 * c.x() + 0.03, 1.05 * c.y(), 0.9 * c.z() + 0.05);
  c += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
  return (255.0 * c.cwiseMax(0.0).cwiseMin(1.0)).array().round().cast<uint8_t>();
}

}  // namespace

void writeSyntheticSurvey(const std::filesystem::path& root, const SyntheticSurvey& survey) {
  std::mt19937 rng(survey.seed);
  std::normal_distribution<double> noise(0.0, 0.005);
  const int side = static_cast<int>(std::lround(20.0 / survey.spacing_m)) + 1;
  scene::PlyData ply;
  for (int i = 0; i < side; ++i) {
    for (int j = 0; j < side; ++j) {
      const double x = -10.0 + i * survey.spacing_m, y = -10.0 + j * survey.spacing_m;
      double up = 0.4 * std::sin(0.6 * x) * std::cos(0.45 * y) + 0.05 * x + noise(rng);
      if (survey.changed && onSyntheticBlock(x, y)) up += 1.0;
      if (survey.changed && onSyntheticGrowth(x, y)) up += 0.3;
      ply.positions.push_back(Eigen::Vector3d(x, y, 20.0 - up) + survey.offset);
      ply.colors.push_back(syntheticColour(x, y, survey.changed, rng));
    }
  }
  std::filesystem::create_directories(root / "dense");
  scene::writePly(root / "dense" / "fused.ply", ply);
  if (!survey.with_mesh) return;
  const uint32_t n = static_cast<uint32_t>(side);
  for (uint32_t i = 0; i + 1 < n; ++i) {
    for (uint32_t j = 0; j + 1 < n; ++j) {
      const uint32_t a = i * n + j, b = a + 1, c = a + n, d = c + 1;
      ply.triangles.push_back({a, c, b});
      ply.triangles.push_back({b, c, d});
    }
  }
  std::filesystem::create_directories(root / "mesh");
  scene::writePly(root / "mesh" / "mesh.ply", ply);
}

}  // namespace auv::recon::change
