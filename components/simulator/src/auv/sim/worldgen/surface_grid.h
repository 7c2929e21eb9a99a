#pragma once
// A structured quad surface (rows x columns of points), the building block of every generated
// shape: rock walls, block faces, the seabed. Its regular layout lets the atlas baker give
// each patch of quads a texture cell sized by its real extent.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "auv/sim/worldgen/materials.h"

namespace auv::sim::worldgen {

/// Quad (r, c) joins points (r, c), (r, c+1), (r+1, c+1), (r+1, c). Builders order points so
/// that d/dc x d/dr points out of the solid (triangles counter-clockwise seen from outside).
struct SurfaceGrid {
  int rows = 0;
  int cols = 0;
  bool wrap = false;  ///< the last column joins the first (a closed band, e.g. a rock wall)
  std::vector<Eigen::Vector3f> points;   ///< m, mesh frame, row-major
  std::vector<Eigen::Vector3f> normals;  ///< unit, per point; computeNormals() fills them
  std::vector<uint8_t> quad_enabled;     ///< per quad, row-major, 0 = left out; empty = all
  Material material = Material::ROCK;
  float texel_size = 0.02f;  ///< m, wanted texture sampling spacing on this surface

  SurfaceGrid() = default;
  SurfaceGrid(int rows, int cols, bool wrap, Material material, float texel_size);

  int quadRows() const { return rows - 1; }
  int quadCols() const { return wrap ? cols : cols - 1; }
  /// Column index after `c`, wrapping around for closed bands.
  int nextCol(int c) const { return wrap && c + 1 == cols ? 0 : c + 1; }
  Eigen::Vector3f& at(int r, int c) { return points[static_cast<size_t>(r) * cols + c]; }
  const Eigen::Vector3f& at(int r, int c) const {
    return points[static_cast<size_t>(r) * cols + c];
  }
  bool quadEnabled(int r, int c) const {
    return quad_enabled.empty() || quad_enabled[static_cast<size_t>(r) * quadCols() + c] != 0;
  }
  /// Total area of the enabled quads (m^2).
  double area() const;
};

/// Unit normals from the points (central differences, d/dc x d/dr). Where the surface
/// collapses to a point or line (a rock's crest), keeps `fallback` normals if given.
void computeNormals(SurfaceGrid& grid, const std::vector<Eigen::Vector3f>* fallback = nullptr);

/// A flat rectangle from `origin` spanned by `along_cols` and `along_rows` (m), split into
/// quads no larger than `spacing`; its outward side is along_cols x along_rows.
SurfaceGrid planarGrid(const Eigen::Vector3f& origin, const Eigen::Vector3f& along_cols,
                       const Eigen::Vector3f& along_rows, float spacing, Material material,
                       float texel_size);

}  // namespace auv::sim::worldgen
