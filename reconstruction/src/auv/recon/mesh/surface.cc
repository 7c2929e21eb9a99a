#include "auv/recon/mesh/surface.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <unordered_map>

#include <open3d/geometry/KDTreeFlann.h>

#include "auv/recon/common/stage_error.h"

namespace auv::recon::mesh {

namespace o3d = open3d::geometry;

void SurfaceOptions::check() const {
  AUV_RECON_CHECK_OPTION(poisson_depth >= 4 && poisson_depth <= 14, poisson_depth,
                         "must be in [4, 14]");
  AUV_RECON_CHECK_OPTION(poisson_scale >= 1.0 && poisson_scale <= 4.0, poisson_scale,
                         "must be in [1, 4]");
  AUV_RECON_CHECK_OPTION(max_edge_factor == 0 || max_edge_factor >= 1.0, max_edge_factor,
                         "must be 0 (off) or >= 1");
  AUV_RECON_CHECK_OPTION(spacing_neighbors >= 1 && spacing_neighbors <= 64, spacing_neighbors,
                         "must be in [1, 64]");
  AUV_RECON_CHECK_OPTION(density_quantile >= 0 && density_quantile < 1, density_quantile,
                         "must be in [0, 1)");
  AUV_RECON_CHECK_OPTION(density_drop_levels >= 0, density_drop_levels, "must be >= 0");
  AUV_RECON_CHECK_OPTION(min_component_fraction >= 0 && min_component_fraction <= 1,
                         min_component_fraction, "must be in [0, 1]");
  AUV_RECON_CHECK_OPTION(min_points >= 4, min_points, "must be >= 4");
  AUV_RECON_CHECK_OPTION(threads == -1 || threads >= 1, threads, "must be -1 (all) or >= 1");
}

namespace {

double quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0;
  const size_t k = std::min(values.size() - 1, static_cast<size_t>(q * values.size()));
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[k];
}

/// Mean distance of cloud point `index` to its `k` nearest other points.
double pointSpacing(const o3d::KDTreeFlann& tree, const o3d::PointCloud& cloud, size_t index,
                    int k) {
  std::vector<int> indices;
  std::vector<double> squared;
  const int found = tree.SearchKNN(cloud.points_[index], k + 1, indices, squared);
  double sum = 0;
  int count = 0;
  for (int i = 0; i < found; ++i) {
    if (static_cast<size_t>(indices[i]) == index) continue;
    sum += std::sqrt(squared[i]);
    ++count;
  }
  return count > 0 ? sum / count : 0;
}

/// Vertex colours from the nearest cloud points (inverse-distance weighted): Open3D's own
/// interpolation through the Poisson octree washes out colours where the octree is coarse.
void colorFromCloud(o3d::TriangleMesh& mesh, const o3d::PointCloud& cloud,
                    const o3d::KDTreeFlann& tree) {
  if (!cloud.HasColors()) return;
  constexpr int kNeighbors = 4;
  mesh.vertex_colors_.assign(mesh.vertices_.size(), Eigen::Vector3d::Zero());
#pragma omp parallel for schedule(dynamic, 256)
  for (size_t v = 0; v < mesh.vertices_.size(); ++v) {
    std::vector<int> indices;
    std::vector<double> squared;
    const int found = tree.SearchKNN(mesh.vertices_[v], kNeighbors, indices, squared);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double weights = 0;
    for (int i = 0; i < found; ++i) {
      const double w = 1.0 / (std::sqrt(squared[i]) + 1e-9);
      sum += w * cloud.colors_[indices[i]];
      weights += w;
    }
    if (weights > 0) mesh.vertex_colors_[v] = sum / weights;
  }
}

}  // namespace

double surfaceArea(const o3d::TriangleMesh& mesh) {
  double area = 0;
  for (const auto& t : mesh.triangles_) {
    area += 0.5 * (mesh.vertices_[t(1)] - mesh.vertices_[t(0)])
                      .cross(mesh.vertices_[t(2)] - mesh.vertices_[t(0)])
                      .norm();
  }
  return area;
}

TrimStats trimSurface(o3d::TriangleMesh& mesh, const std::vector<double>& densities,
                      const o3d::PointCloud& cloud, double finest_cell,
                      const SurfaceOptions& options) {
  TrimStats stats;
  stats.poisson_vertices = mesh.vertices_.size();
  stats.poisson_triangles = mesh.triangles_.size();
  stats.finest_cell = finest_cell;
  const size_t num_triangles = mesh.triangles_.size();
  std::vector<bool> remove(num_triangles, false);

  // Long edges ([76]): in unobserved areas the Poisson octree is coarse and its triangles large
  // compared with the sampling. The length scale is the spacing of the cloud point nearest to
  // the triangle (cached per point), never below the finest octree cell.
  o3d::KDTreeFlann tree(cloud);
  {
    std::vector<double> sample;
    const size_t step = std::max<size_t>(1, cloud.points_.size() / 2000);
    for (size_t i = 0; i < cloud.points_.size(); i += step) {
      sample.push_back(pointSpacing(tree, cloud, i, options.spacing_neighbors));
    }
    stats.median_spacing = quantile(sample, 0.5);
  }
  if (options.max_edge_factor > 0) {
    std::vector<int> nearest_point(num_triangles, -1);
    std::vector<double> longest_edge(num_triangles, 0.0);
#pragma omp parallel for schedule(dynamic, 256)
    for (size_t t = 0; t < num_triangles; ++t) {
      const auto& tri = mesh.triangles_[t];
      const Eigen::Vector3d& a = mesh.vertices_[tri(0)];
      const Eigen::Vector3d& b = mesh.vertices_[tri(1)];
      const Eigen::Vector3d& c = mesh.vertices_[tri(2)];
      longest_edge[t] = std::max({(a - b).norm(), (b - c).norm(), (c - a).norm()});
      std::vector<int> nearest(1);
      std::vector<double> squared(1);
      if (tree.SearchKNN(Eigen::Vector3d((a + b + c) / 3.0), 1, nearest, squared) == 1) {
        nearest_point[t] = nearest[0];
      }
    }
    // Spacing once per distinct nearest point.
    std::vector<int> points(nearest_point);
    std::sort(points.begin(), points.end());
    points.erase(std::unique(points.begin(), points.end()), points.end());
    std::unordered_map<int, double> spacing;
    std::vector<double> values(points.size(), 0.0);
#pragma omp parallel for schedule(dynamic, 256)
    for (size_t i = 0; i < points.size(); ++i) {
      if (points[i] >= 0)
        values[i] = pointSpacing(tree, cloud, points[i], options.spacing_neighbors);
    }
    for (size_t i = 0; i < points.size(); ++i) spacing[points[i]] = values[i];
    for (size_t t = 0; t < num_triangles; ++t) {
      if (nearest_point[t] < 0) continue;
      const double scale = std::max(spacing[nearest_point[t]], finest_cell);
      remove[t] = longest_edge[t] > options.max_edge_factor * scale;
    }
    stats.removed_long_edges = std::count(remove.begin(), remove.end(), true);
  }

  // Low density: Open3D's densities are the log2 sample depths of the Poisson solver, low
  // where few samples support the surface (the closure of an open surface).
  if (!densities.empty() && (options.density_quantile > 0 || options.density_drop_levels > 0)) {
    double threshold = -std::numeric_limits<double>::infinity();
    if (options.density_quantile > 0) threshold = quantile(densities, options.density_quantile);
    if (options.density_drop_levels > 0) {
      threshold = std::max(threshold, quantile(densities, 0.5) - options.density_drop_levels);
    }
    stats.density_threshold = threshold;
    for (size_t t = 0; t < num_triangles; ++t) {
      if (remove[t]) continue;
      const auto& tri = mesh.triangles_[t];
      if (densities[tri(0)] < threshold || densities[tri(1)] < threshold ||
          densities[tri(2)] < threshold) {
        remove[t] = true;
        ++stats.removed_low_density;
      }
    }
  }
  mesh.RemoveTrianglesByMask(remove);
  mesh.RemoveUnreferencedVertices();

  // Small components left floating by the trimming.
  if (options.min_component_fraction > 0 && !mesh.triangles_.empty()) {
    const auto [cluster_of, cluster_sizes, cluster_areas] = mesh.ClusterConnectedTriangles();
    (void)cluster_areas;
    const size_t largest = *std::max_element(cluster_sizes.begin(), cluster_sizes.end());
    const double keep = options.min_component_fraction * static_cast<double>(largest);
    std::vector<bool> small(mesh.triangles_.size(), false);
    for (size_t t = 0; t < cluster_of.size(); ++t) {
      const size_t size = cluster_sizes[cluster_of[t]];
      small[t] = static_cast<double>(size) < keep ||
                 (options.min_component_fraction >= 1.0 && size < largest);
    }
    stats.removed_components = std::count(small.begin(), small.end(), true);
    mesh.RemoveTrianglesByMask(small);
    mesh.RemoveUnreferencedVertices();
  }
  stats.vertices = mesh.vertices_.size();
  stats.triangles = mesh.triangles_.size();
  colorFromCloud(mesh, cloud, tree);
  return stats;
}

SurfaceResult reconstructSurface(const o3d::PointCloud& cloud, const SurfaceOptions& options) {
  options.check();
  if (cloud.points_.size() < options.min_points) {
    throw StageError("mesh",
                     "the dense cloud has " + std::to_string(cloud.points_.size()) +
                         " points, fewer than min_points = " + std::to_string(options.min_points) +
                         " (too little was matched densely)");
  }
  if (!cloud.HasNormals()) {
    throw StageError("mesh", "the dense cloud has no normals (Poisson needs oriented points)");
  }
  SurfaceResult result;
  auto [poisson, densities] = o3d::TriangleMesh::CreateFromPointCloudPoisson(
      cloud, static_cast<size_t>(options.poisson_depth), 0.0f,
      static_cast<float>(options.poisson_scale), options.poisson_linear_fit, options.threads);
  if (!poisson || poisson->triangles_.empty()) {
    throw StageError("mesh", "Poisson reconstruction produced no surface from " +
                                 std::to_string(cloud.points_.size()) + " points");
  }
  result.untrimmed = poisson;
  result.densities = densities;
  const Eigen::Vector3d extent = cloud.GetMaxBound() - cloud.GetMinBound();
  const double finest_cell =
      extent.maxCoeff() * options.poisson_scale / std::pow(2.0, options.poisson_depth);
  result.trimmed = std::make_shared<o3d::TriangleMesh>(*poisson);
  result.stats = trimSurface(*result.trimmed, densities, cloud, finest_cell, options);
  if (result.trimmed->triangles_.empty()) {
    throw StageError("mesh", "trimming removed all " +
                                 std::to_string(result.stats.poisson_triangles) +
                                 " Poisson triangles (cloud too sparse or noisy; try a lower "
                                 "poisson_depth or a larger max_edge_factor)");
  }
  result.trimmed->ComputeVertexNormals();
  return result;
}

}  // namespace auv::recon::mesh
