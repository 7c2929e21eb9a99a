#include "auv/recon/change/m3c2.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>

#include "auv/recon/change/indexed_cloud.h"
#include "auv/recon/common/stage_error.h"

namespace auv::recon::change {

void M3C2Options::check() const {
  AUV_RECON_CHECK_OPTION(normal_scale_m > 0, normal_scale_m, "must be > 0");
  AUV_RECON_CHECK_OPTION(projection_scale_m > 0, projection_scale_m, "must be > 0");
  AUV_RECON_CHECK_OPTION(max_depth_m > 0, max_depth_m, "must be > 0");
  AUV_RECON_CHECK_OPTION(min_points >= 2, min_points, "must be >= 2 (a spread needs two)");
  AUV_RECON_CHECK_OPTION(registration_error_m >= 0, registration_error_m, "must be >= 0");
  AUV_RECON_CHECK_OPTION(confidence_z > 0, confidence_z, "must be > 0");
  AUV_RECON_CHECK_OPTION(max_axis_angle_deg > 0 && max_axis_angle_deg <= 90, max_axis_angle_deg,
                         "must be in (0, 90]");
  if (!(orientation.norm() > 0) || !orientation.allFinite()) {
    throw OptionError("orientation: must be a non-zero vector");
  }
}

namespace {

/// Unit normal of the least-squares plane through the points (zero with fewer than three or
/// when they are collinear).
Eigen::Vector3d planeNormal(const IndexedCloud& a, const std::vector<int>& in_a,
                            const IndexedCloud& b, const std::vector<int>& in_b) {
  const size_t n = in_a.size() + in_b.size();
  if (n < 3) return Eigen::Vector3d::Zero();
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int i : in_a) mean += a[i];
  for (int i : in_b) mean += b[i];
  mean /= static_cast<double>(n);
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (int i : in_a) covariance += (a[i] - mean) * (a[i] - mean).transpose();
  for (int i : in_b) covariance += (b[i] - mean) * (b[i] - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  // Collinear points: the two smallest eigenvalues vanish together, no plane is defined.
  if (solver.eigenvalues()(1) <= 1e-12 * std::max(solver.eigenvalues()(2), 1e-300)) {
    return Eigen::Vector3d::Zero();
  }
  return solver.eigenvectors().col(0);
}

struct AxisStatistics {
  int count = 0;
  int sources = 0;  ///< distinct sources of the points (0 without `sources`)
  double mean = 0.0, spread = 0.0;
};

/// Mean and standard deviation of the positions along `normal` of the cloud's points inside
/// the cylinder around `core`, and how many distinct sources they came from. Points whose
/// own normal is farther than `min_cos_to_axis` allows lie along the axis and are left out.
AxisStatistics alongAxis(const IndexedCloud& cloud, const M3C2Cloud& input,
                         const Eigen::Vector3d& core, const Eigen::Vector3d& normal,
                         const M3C2Options& options, double min_cos_to_axis) {
  const double radius = 0.5 * options.projection_scale_m;
  const double depth = options.max_depth_m;
  // The cylinder is searched as a row of short segments, each inside a small sphere: one
  // sphere around a long cylinder holds several times more of a surface crossing it. Each
  // segment keeps only the points of its own slab along the axis, so none counts twice.
  const double half = std::min(radius, depth);
  const int segments = static_cast<int>(std::ceil(depth / half - 1e-9));
  const double sphere = std::hypot(radius, half);
  AxisStatistics s;
  double sum = 0.0, sum2 = 0.0;
  std::vector<uint32_t> seen;  // source ids, duplicates included
  for (int j = 0; j < segments; ++j) {
    const double low = -depth + 2.0 * half * j;
    const double high = j + 1 == segments ? depth : low + 2.0 * half;
    for (int i : cloud.within(core + (low + half) * normal, sphere)) {
      const Eigen::Vector3d offset = cloud[i] - core;
      const double along = offset.dot(normal);
      if (along < low || along > high || (along == high && j + 1 < segments)) continue;
      if ((offset - along * normal).squaredNorm() > radius * radius) continue;
      if (input.normals && std::abs((*input.normals)[i].dot(normal)) < min_cos_to_axis) continue;
      ++s.count;
      sum += along;
      sum2 += along * along;
      if (input.sources) {
        const size_t p = static_cast<size_t>(i);
        seen.insert(seen.end(), input.sources->ids.begin() + input.sources->offsets[p],
                    input.sources->ids.begin() + input.sources->offsets[p + 1]);
      }
    }
  }
  if (s.count == 0) return s;
  std::sort(seen.begin(), seen.end());
  s.sources = static_cast<int>(std::unique(seen.begin(), seen.end()) - seen.begin());
  s.mean = sum / s.count;
  // Sample standard deviation; clamped at 0 against rounding.
  s.spread = s.count > 1
                 ? std::sqrt(std::max(0.0, (sum2 - s.count * s.mean * s.mean) / (s.count - 1)))
                 : 0.0;
  return s;
}

void checkCloud(const M3C2Cloud& cloud, const char* which) {
  const size_t size = cloud.points.size();
  if (cloud.sources && (cloud.sources->size() != size ||
                        cloud.sources->offsets.back() != cloud.sources->ids.size())) {
    throw std::invalid_argument(std::string("m3c2: the sources of ") + which + " list " +
                                std::to_string(cloud.sources->size()) + " points for " +
                                std::to_string(size));
  }
  if (cloud.normals && cloud.normals->size() != size) {
    throw std::invalid_argument(std::string("m3c2: ") + which + " has " +
                                std::to_string(cloud.normals->size()) + " normals for " +
                                std::to_string(size) + " points");
  }
}

}  // namespace

double levelOfDetection(const M3C2Point& p, double registration_error_m, double confidence_z) {
  return confidence_z * (std::sqrt(p.spread1 * p.spread1 / p.independent1() +
                                   p.spread2 * p.spread2 / p.independent2()) +
                         registration_error_m);
}

std::vector<M3C2Point> m3c2(const std::vector<Eigen::Vector3d>& cloud1,
                            const std::vector<Eigen::Vector3d>& cloud2,
                            const std::vector<Eigen::Vector3d>& core_points,
                            const M3C2Options& options,
                            const std::vector<Eigen::Vector3d>& orientation_hints,
                            const PointSources* sources1, const PointSources* sources2) {
  return m3c2(M3C2Cloud{cloud1, sources1}, M3C2Cloud{cloud2, sources2}, core_points, options,
              orientation_hints);
}

std::vector<M3C2Point> m3c2(const M3C2Cloud& cloud1, const M3C2Cloud& cloud2,
                            const std::vector<Eigen::Vector3d>& core_points,
                            const M3C2Options& options,
                            const std::vector<Eigen::Vector3d>& orientation_hints) {
  options.check();
  if (!orientation_hints.empty() && orientation_hints.size() != core_points.size()) {
    throw std::invalid_argument("m3c2: " + std::to_string(orientation_hints.size()) +
                                " orientation hints for " + std::to_string(core_points.size()) +
                                " core points");
  }
  checkCloud(cloud1, "cloud 1");
  checkCloud(cloud2, "cloud 2");
  const IndexedCloud first(cloud1.points);
  const IndexedCloud second(cloud2.points);
  // Slightly below the cosine so that 90 degrees lets every point in, rounding included.
  const double min_cos_to_axis =
      std::cos(options.max_axis_angle_deg * 3.14159265358979323846 / 180.0) - 1e-12;
  std::vector<M3C2Point> result(core_points.size());
  const double normal_radius = 0.5 * options.normal_scale_m;
#pragma omp parallel for schedule(dynamic, 64)
  for (long k = 0; k < static_cast<long>(core_points.size()); ++k) {
    const size_t c = static_cast<size_t>(k);
    const Eigen::Vector3d& core = core_points[c];
    M3C2Point& out = result[c];
    // Cloud 1's surface defines the normal; where it is too sparse, both clouds together.
    std::vector<int> near1 = first.within(core, normal_radius);
    Eigen::Vector3d normal = planeNormal(first, near1, second, {});
    if (normal.isZero()) {
      normal = planeNormal(first, near1, second, second.within(core, normal_radius));
    }
    if (normal.isZero()) continue;
    const Eigen::Vector3d hint =
        orientation_hints.empty() ? options.orientation : orientation_hints[c];
    if (normal.dot(hint) < 0) normal = -normal;
    out.normal = normal;
    const AxisStatistics s1 = alongAxis(first, cloud1, core, normal, options, min_cos_to_axis);
    const AxisStatistics s2 = alongAxis(second, cloud2, core, normal, options, min_cos_to_axis);
    out.count1 = s1.count;
    out.count2 = s2.count;
    out.sources1 = s1.sources;
    out.sources2 = s2.sources;
    out.spread1 = s1.spread;
    out.spread2 = s2.spread;
    if (s1.count < options.min_points || s2.count < options.min_points) continue;
    out.distance = s2.mean - s1.mean;
    out.level_of_detection =
        levelOfDetection(out, options.registration_error_m, options.confidence_z);
    out.significant = std::abs(out.distance) > out.level_of_detection;
  }
  return result;
}

}  // namespace auv::recon::change
