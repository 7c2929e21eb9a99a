#include "auv/sim/worldgen/surface_grid.h"

#include <algorithm>
#include <cmath>

namespace auv::sim::worldgen {

SurfaceGrid::SurfaceGrid(int rows_, int cols_, bool wrap_, Material material_, float texel_size_)
    : rows(rows_),
      cols(cols_),
      wrap(wrap_),
      points(static_cast<size_t>(rows_) * cols_, Eigen::Vector3f::Zero()),
      material(material_),
      texel_size(texel_size_) {}

double SurfaceGrid::area() const {
  double total = 0.0;
  for (int r = 0; r < quadRows(); ++r) {
    for (int c = 0; c < quadCols(); ++c) {
      if (!quadEnabled(r, c)) continue;
      const int c1 = nextCol(c);
      const Eigen::Vector3f& a = at(r, c);
      total += 0.5 * (at(r, c1) - a).cross(at(r + 1, c1) - a).norm();
      total += 0.5 * (at(r + 1, c1) - a).cross(at(r + 1, c) - a).norm();
    }
  }
  return total;
}

void computeNormals(SurfaceGrid& grid, const std::vector<Eigen::Vector3f>* fallback) {
  std::vector<Eigen::Vector3f> normals(grid.points.size(), Eigen::Vector3f::UnitZ());
  for (int r = 0; r < grid.rows; ++r) {
    const int r0 = std::max(r - 1, 0), r1 = std::min(r + 1, grid.rows - 1);
    for (int c = 0; c < grid.cols; ++c) {
      int c0 = c - 1, c1 = c + 1;
      if (grid.wrap) {
        c0 = (c0 + grid.cols) % grid.cols;
        c1 = c1 % grid.cols;
      } else {
        c0 = std::max(c0, 0);
        c1 = std::min(c1, grid.cols - 1);
      }
      const Eigen::Vector3f along_cols = grid.at(r, c1) - grid.at(r, c0);
      const Eigen::Vector3f along_rows = grid.at(r1, c) - grid.at(r0, c);
      const Eigen::Vector3f n = along_cols.cross(along_rows);
      const size_t i = static_cast<size_t>(r) * grid.cols + c;
      const float length = n.norm();
      // A tiny cross product means the grid collapsed here (a crest): its direction is noise.
      const float scale = along_cols.norm() * along_rows.norm();
      if (length > 1e-3f * scale && length > 1e-12f) {
        normals[i] = n / length;
      } else if (fallback && i < fallback->size()) {
        normals[i] = (*fallback)[i];
      }
    }
  }
  grid.normals = std::move(normals);
}

SurfaceGrid planarGrid(const Eigen::Vector3f& origin, const Eigen::Vector3f& along_cols,
                       const Eigen::Vector3f& along_rows, float spacing, Material material,
                       float texel_size) {
  const int quads_c = std::max(1, static_cast<int>(std::ceil(along_cols.norm() / spacing)));
  const int quads_r = std::max(1, static_cast<int>(std::ceil(along_rows.norm() / spacing)));
  SurfaceGrid grid(quads_r + 1, quads_c + 1, false, material, texel_size);
  for (int r = 0; r <= quads_r; ++r) {
    for (int c = 0; c <= quads_c; ++c) {
      grid.at(r, c) = origin + along_cols * (static_cast<float>(c) / quads_c) +
                      along_rows * (static_cast<float>(r) / quads_r);
    }
  }
  const Eigen::Vector3f n = along_cols.cross(along_rows).normalized();
  grid.normals.assign(grid.points.size(), n);
  return grid;
}

}  // namespace auv::sim::worldgen
