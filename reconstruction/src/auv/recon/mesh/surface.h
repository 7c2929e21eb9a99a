#pragma once
// Surface reconstruction (docs/paper.md §3.6): screened Poisson reconstruction of the oriented
// dense cloud (Kazhdan and Hoppe 2013, through Open3D), then removal of the false surfaces the
// watertight indicator function closes over unobserved areas: triangles with an edge much
// longer than the local sampling (the paper's reference [76]) and vertices of low Poisson
// density (few samples nearby), optionally keeping only the large connected components.

#include <cstddef>
#include <memory>
#include <vector>

#include <open3d/geometry/PointCloud.h>
#include <open3d/geometry/TriangleMesh.h>

namespace auv::recon::mesh {

struct SurfaceOptions {
  /// Poisson octree depth: finest cell = (cloud extent x scale) / 2^depth.
  int poisson_depth = 9;
  /// Poisson bounding cube = cloud extent x this (> 1 leaves room around the samples).
  double poisson_scale = 1.1;
  /// Poisson: linear interpolation of the iso-value positions (smoother on noisy data).
  bool poisson_linear_fit = false;
  /// Long-edge trimming: a triangle is removed when its longest edge exceeds this factor times
  /// the local length scale, max(local point spacing, finest Poisson cell). 0 disables it.
  double max_edge_factor = 4.0;
  /// Neighbours averaged for the local point spacing (mean distance to them).
  int spacing_neighbors = 8;
  /// Density trimming: vertices whose Poisson density is below this quantile of all densities
  /// are removed (with their triangles). 0 disables it.
  double density_quantile = 0.02;
  /// Density trimming, absolute: vertices whose density is more than this many octree levels
  /// below the median density are removed too (densities are log2 sample depths). 0 disables.
  double density_drop_levels = 1.5;
  /// Connected components with fewer triangles than this fraction of the largest one are
  /// removed after trimming (0 keeps them all, 1 keeps only the largest).
  double min_component_fraction = 0.02;
  /// Fewer points than this in the cloud: StageError (nothing to reconstruct).
  size_t min_points = 100;
  /// Threads for Poisson (-1: all cores).
  int threads = -1;

  /// Throws OptionError naming the field and its value.
  void check() const;
};

/// What the trimming removed, for report.json.
struct TrimStats {
  size_t poisson_vertices = 0, poisson_triangles = 0;
  size_t removed_long_edges = 0;       ///< triangles
  size_t removed_low_density = 0;      ///< triangles (touching a low-density vertex)
  size_t removed_components = 0;       ///< triangles in small components
  size_t vertices = 0, triangles = 0;  ///< after trimming
  double finest_cell = 0;              ///< m (cloud units)
  double median_spacing = 0;     ///< m, mean distance to spacing_neighbors, median over points
  double density_threshold = 0;  ///< densities below were removed
};

struct SurfaceResult {
  std::shared_ptr<open3d::geometry::TriangleMesh> untrimmed;  ///< Poisson output
  std::vector<double> densities;                              ///< per untrimmed vertex
  std::shared_ptr<open3d::geometry::TriangleMesh> trimmed;
  TrimStats stats;
};

/// Poisson + trimming. The cloud must have normals (oriented outwards, towards the cameras).
/// Throws StageError("mesh", ...) for a cloud with too few points, without normals, or when
/// trimming leaves nothing; OptionError for bad options.
SurfaceResult reconstructSurface(const open3d::geometry::PointCloud& cloud,
                                 const SurfaceOptions& options);

/// Trimming alone (exposed for tests): removes from `mesh` the long-edge triangles and
/// low-density vertices given the cloud it came from and its per-vertex densities.
TrimStats trimSurface(open3d::geometry::TriangleMesh& mesh, const std::vector<double>& densities,
                      const open3d::geometry::PointCloud& cloud, double finest_cell,
                      const SurfaceOptions& options);

/// Total area of the triangles of `mesh`, m^2.
double surfaceArea(const open3d::geometry::TriangleMesh& mesh);

}  // namespace auv::recon::mesh
