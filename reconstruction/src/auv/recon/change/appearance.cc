#include "auv/recon/change/appearance.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "auv/recon/change/clusters.h"
#include "auv/recon/change/indexed_cloud.h"
#include "auv/recon/common/stage_error.h"

namespace auv::recon::change {

void AppearanceOptions::check() const {
  AUV_RECON_CHECK_OPTION(radius_m > 0, radius_m, "must be > 0");
  AUV_RECON_CHECK_OPTION(min_points >= 1, min_points, "must be >= 1");
  AUV_RECON_CHECK_OPTION(min_delta_e >= 0, min_delta_e, "must be >= 0");
  AUV_RECON_CHECK_OPTION(threshold_sigmas > 0, threshold_sigmas, "must be > 0");
}

Eigen::Vector3d srgbToLab(const Eigen::Vector3d& rgb) {
  auto linear = [](double c) {
    return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
  };
  const Eigen::Vector3d l(linear(rgb.x()), linear(rgb.y()), linear(rgb.z()));
  Eigen::Matrix3d to_xyz;
  to_xyz << 0.4124, 0.3576, 0.1805, 0.2126, 0.7152, 0.0722, 0.0193, 0.1192, 0.9505;
  const Eigen::Vector3d xyz = (to_xyz * l).cwiseQuotient(Eigen::Vector3d(0.95047, 1.0, 1.08883));
  auto f = [](double t) {
    return t > 216.0 / 24389.0 ? std::cbrt(t) : (24389.0 / 27.0 * t + 16.0) / 116.0;
  };
  const double fx = f(xyz.x()), fy = f(xyz.y()), fz = f(xyz.z());
  return {116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)};
}

namespace {

double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

/// Least-squares line y = gain * x + offset, refitted three times on the 80 % of pairs it
/// fits best (a few changed places must not bend it). A channel that hardly varies over the
/// site (robust sigma, 1.4826 MAD, under 0.02: a few changed places do not count) does not
/// fix a gain: only an offset, the median of y - x.
std::pair<double, double> robustLine(const std::vector<double>& x, const std::vector<double>& y) {
  if (x.empty()) return {1.0, 0.0};
  const double centre = median(x);
  std::vector<double> deviations;
  for (double v : x) deviations.push_back(std::abs(v - centre));
  if (1.4826 * median(deviations) < 0.02) {
    std::vector<double> shift;
    for (size_t i = 0; i < x.size(); ++i) shift.push_back(y[i] - x[i]);
    return {1.0, median(shift)};
  }
  std::vector<size_t> used(x.size());
  for (size_t i = 0; i < used.size(); ++i) used[i] = i;
  double gain = 1.0, offset = 0.0;
  for (int round = 0; round < 4; ++round) {
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (size_t i : used) sx += x[i], sy += y[i], sxx += x[i] * x[i], sxy += x[i] * y[i];
    const double n = static_cast<double>(used.size());
    const double det = n * sxx - sx * sx;
    if (n < 2 || std::abs(det) < 1e-12) break;
    gain = (n * sxy - sx * sy) / det;
    offset = (sy - gain * sx) / n;
    std::vector<size_t> all(x.size());
    for (size_t i = 0; i < all.size(); ++i) all[i] = i;
    std::sort(all.begin(), all.end(), [&](size_t a, size_t b) {
      return std::abs(gain * x[a] + offset - y[a]) < std::abs(gain * x[b] + offset - y[b]);
    });
    all.resize(std::max<size_t>(2, all.size() * 8 / 10));
    used = all;
  }
  return {gain, offset};
}

}  // namespace

AppearanceResult compareAppearance(const std::vector<Eigen::Vector3d>& cloud1,
                                   const std::vector<Eigen::Vector3d>& colors1,
                                   const std::vector<Eigen::Vector3d>& cloud2,
                                   const std::vector<Eigen::Vector3d>& colors2,
                                   const std::vector<Eigen::Vector3d>& core_points,
                                   const std::vector<char>& exclude,
                                   const AppearanceOptions& options) {
  options.check();
  const size_t n = core_points.size();
  AppearanceResult result;
  result.delta_e.assign(n, std::numeric_limits<double>::quiet_NaN());
  result.significant.assign(n, 0);
  if (colors1.size() != cloud1.size() || colors2.size() != cloud2.size()) return result;
  const IndexedCloud first(cloud1), second(cloud2);
  // Mean colour of each cloud near each core point.
  std::vector<Eigen::Vector3d> mean1(n), mean2(n);
  std::vector<char> measured(n, 0);
  for (size_t i = 0; i < n; ++i) {
    if (!exclude.empty() && exclude[i]) continue;
    const std::vector<int> in1 = first.within(core_points[i], options.radius_m);
    const std::vector<int> in2 = second.within(core_points[i], options.radius_m);
    if (static_cast<int>(in1.size()) < options.min_points ||
        static_cast<int>(in2.size()) < options.min_points)
      continue;
    mean1[i].setZero();
    mean2[i].setZero();
    for (int k : in1) mean1[i] += colors1[static_cast<size_t>(k)];
    for (int k : in2) mean2[i] += colors2[static_cast<size_t>(k)];
    mean1[i] /= static_cast<double>(in1.size());
    mean2[i] /= static_cast<double>(in2.size());
    measured[i] = 1;
  }
  // Survey 2's colours brought to survey 1's, channel by channel.
  for (int c = 0; c < 3; ++c) {
    std::vector<double> x, y;
    for (size_t i = 0; i < n; ++i)
      if (measured[i]) x.push_back(mean2[i][c]), y.push_back(mean1[i][c]);
    std::tie(result.gain[c], result.offset[c]) = robustLine(x, y);
  }
  std::vector<double> differences;
  for (size_t i = 0; i < n; ++i) {
    if (!measured[i]) continue;
    const Eigen::Vector3d normalised =
        (result.gain.cwiseProduct(mean2[i]) + result.offset).cwiseMax(0.0).cwiseMin(1.0);
    result.delta_e[i] = (srgbToLab(mean1[i]) - srgbToLab(normalised)).norm();
    differences.push_back(result.delta_e[i]);
  }
  result.measured = differences.size();
  result.median_delta_e = median(differences);
  std::vector<double> deviations;
  for (double d : differences) deviations.push_back(std::abs(d - result.median_delta_e));
  result.threshold =
      std::max(options.min_delta_e,
               result.median_delta_e + options.threshold_sigmas * 1.4826 * median(deviations));
  for (size_t i = 0; i < n; ++i) {
    result.significant[i] = measured[i] && result.delta_e[i] > result.threshold;
    result.significant_count += static_cast<size_t>(result.significant[i]);
  }
  return result;
}

nlohmann::json appearanceClusterJson(const AppearanceCluster& c) {
  return {{"area_m2", c.area_m2},
          {"core_points", c.core_points.size()},
          {"mean_delta_e", c.mean_delta_e},
          {"max_delta_e", c.max_delta_e},
          {"centroid", {c.centroid.x(), c.centroid.y(), c.centroid.z()}}};
}

std::vector<AppearanceCluster> clusterAppearance(const std::vector<Eigen::Vector3d>& core_points,
                                                 const AppearanceResult& result, double spacing_m,
                                                 double link_m, double min_area_m2) {
  std::vector<AppearanceCluster> clusters;
  for (std::vector<size_t>& group : linkFlagged(core_points, result.significant, link_m)) {
    AppearanceCluster cluster;
    const double n = static_cast<double>(group.size());
    cluster.area_m2 = n * spacing_m * spacing_m;
    if (cluster.area_m2 < min_area_m2) continue;
    for (size_t i : group) {
      cluster.mean_delta_e += result.delta_e[i] / n;
      cluster.max_delta_e = std::max(cluster.max_delta_e, result.delta_e[i]);
      cluster.centroid += core_points[i] / n;
    }
    cluster.core_points = std::move(group);
    clusters.push_back(std::move(cluster));
  }
  std::sort(
      clusters.begin(), clusters.end(),
      [](const AppearanceCluster& a, const AppearanceCluster& b) { return a.area_m2 > b.area_m2; });
  return clusters;
}

}  // namespace auv::recon::change
