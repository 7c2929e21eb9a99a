#include "auv/recon/change/local_bias.h"

#include <algorithm>
#include <cmath>

#include "auv/recon/change/indexed_cloud.h"

namespace auv::recon::change {
namespace {

double median(std::vector<double>& values) {
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

}  // namespace

LocalBias removeLocalBias(const std::vector<Eigen::Vector3d>& core_points,
                          std::vector<M3C2Point>& comparison, double radius_m, int min_neighbours) {
  LocalBias result;
  result.bias.assign(comparison.size(), 0.0);
  std::vector<Eigen::Vector3d> measured_points;
  std::vector<size_t> measured;
  for (size_t i = 0; i < comparison.size(); ++i) {
    if (!comparison[i].valid()) continue;
    measured.push_back(i);
    measured_points.push_back(core_points[i]);
  }
  if (measured.empty()) return result;
  const IndexedCloud cloud(measured_points);
#pragma omp parallel for schedule(dynamic, 64)
  for (long k = 0; k < static_cast<long>(measured.size()); ++k) {
    const std::vector<int> near = cloud.within(measured_points[static_cast<size_t>(k)], radius_m);
    if (static_cast<int>(near.size()) < min_neighbours) continue;
    std::vector<double> distances;
    distances.reserve(near.size());
    for (int j : near) distances.push_back(comparison[measured[static_cast<size_t>(j)]].distance);
    result.bias[measured[static_cast<size_t>(k)]] = median(distances);
  }
  std::vector<double> corrected, magnitude;
  for (size_t i : measured) {
    comparison[i].distance -= result.bias[i];
    corrected.push_back(comparison[i].distance);
    magnitude.push_back(std::abs(result.bias[i]));
  }
  const double centre = median(corrected);
  std::vector<double> deviations;
  for (double d : corrected) deviations.push_back(std::abs(d - centre));
  result.residual_sigma_m = 1.4826 * median(deviations);
  result.median_abs_bias_m = median(magnitude);
  return result;
}

void applyLevelOfDetection(std::vector<M3C2Point>& comparison, double registration_error_m,
                           double confidence_z) {
  for (M3C2Point& p : comparison) {
    if (!p.valid()) continue;
    p.level_of_detection = levelOfDetection(p, registration_error_m, confidence_z);
    p.significant = std::abs(p.distance) > p.level_of_detection;
  }
}

}  // namespace auv::recon::change
