#include <meshoptimizer.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "auv/view/mesh.h"

namespace auv::view {

namespace {

/// `mesh` with only the vertices `index` uses, renumbered in first-use order (what the GPU
/// fetches stays local, and a coarse level does not carry the original's vertex buffer).
TexturedMesh compact(const TexturedMesh& mesh, const std::vector<uint32_t>& index,
                     const std::vector<TexturedMesh::Group>& groups) {
  TexturedMesh out;
  out.groups = groups;
  std::vector<uint32_t> remap(mesh.position.size() / 3, UINT32_MAX);
  out.index.reserve(index.size());
  for (uint32_t v : index) {
    if (remap[v] == UINT32_MAX) {
      remap[v] = static_cast<uint32_t>(out.position.size() / 3);
      out.position.insert(out.position.end(), mesh.position.begin() + 3 * v,
                          mesh.position.begin() + 3 * v + 3);
      out.uv.insert(out.uv.end(), mesh.uv.begin() + 2 * v, mesh.uv.begin() + 2 * v + 2);
    }
    out.index.push_back(remap[v]);
  }
  return out;
}

}  // namespace

std::vector<MeshLevel> buildLevels(const TexturedMesh& mesh, size_t min_triangles) {
  std::vector<MeshLevel> levels;
  levels.push_back({mesh, 0.f});
  while (levels.back().mesh.triangles() > min_triangles) {
    const TexturedMesh& previous = levels.back().mesh;
    std::vector<uint32_t> index;
    std::vector<TexturedMesh::Group> groups;
    float worst = 0;
    for (const auto& group : previous.groups) {
      const size_t target = std::max<size_t>(group.index_count / 2 / 3 * 3, 3);
      std::vector<uint32_t> out(group.index_count);
      float error = 0;
      // Target error 5 % of the extent: the triangle count decides, not the error bound.
      const size_t count =
          meshopt_simplify(out.data(), previous.index.data() + group.first_index, group.index_count,
                           previous.position.data(), previous.position.size() / 3,
                           3 * sizeof(float), target, 0.05f, meshopt_SimplifyLockBorder, &error);
      worst = std::max(worst, error);
      TexturedMesh::Group g = group;
      g.first_index = index.size();
      g.index_count = count;
      index.insert(index.end(), out.begin(), out.begin() + count);
      if (count > 0) groups.push_back(g);
    }
    if (index.size() > previous.index.size() * 8 / 10) break;  // no longer worth a level
    levels.push_back({compact(previous, index, groups), worst});
  }
  return levels;
}

std::vector<Tile> tileMesh(TexturedMesh& mesh, size_t triangles_per_tile) {
  const size_t n = mesh.position.size() / 3;
  std::array<float, 3> lo{1e30f, 1e30f, 1e30f}, hi{-1e30f, -1e30f, -1e30f};
  for (size_t v = 0; v < n; ++v) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], mesh.position[3 * v + k]);
      hi[k] = std::max(hi[k], mesh.position[3 * v + k]);
    }
  }
  // The two longest extents: a seabed spreads in x, y; a wall or a canyon side may not.
  std::array<int, 3> axes{0, 1, 2};
  std::sort(axes.begin(), axes.end(), [&](int a, int b) { return hi[a] - lo[a] > hi[b] - lo[b]; });
  const int side = static_cast<int>(
      std::clamp<double>(std::floor(std::sqrt(static_cast<double>(mesh.triangles()) /
                                              std::max<size_t>(triangles_per_tile, 1))),
                         1, 16));
  auto cell = [&](float value, int axis) {
    const float extent = std::max(hi[axis] - lo[axis], 1e-6f);
    return std::min(side - 1, static_cast<int>((value - lo[axis]) / extent * side));
  };
  // Triangles by (tile, page).
  const size_t tiles = static_cast<size_t>(side * side), pages = mesh.groups.size();
  std::vector<std::vector<uint32_t>> bucket(tiles * pages);
  for (size_t g = 0; g < pages; ++g) {
    const auto& group = mesh.groups[g];
    for (size_t i = group.first_index; i < group.first_index + group.index_count; i += 3) {
      float c[3] = {0, 0, 0};
      for (int corner = 0; corner < 3; ++corner) {
        for (int k = 0; k < 3; ++k) c[k] += mesh.position[3 * mesh.index[i + corner] + k] / 3;
      }
      const size_t t =
          static_cast<size_t>(cell(c[axes[0]], axes[0]) + side * cell(c[axes[1]], axes[1]));
      bucket[t * pages + g].insert(bucket[t * pages + g].end(), mesh.index.begin() + i,
                                   mesh.index.begin() + i + 3);
    }
  }
  std::vector<Tile> out;
  std::vector<uint32_t> index;
  std::vector<TexturedMesh::Group> groups;
  index.reserve(mesh.index.size());
  for (size_t t = 0; t < tiles; ++t) {
    Tile tile;
    std::array<float, 3> tlo{1e30f, 1e30f, 1e30f}, thi{-1e30f, -1e30f, -1e30f};
    for (size_t g = 0; g < pages; ++g) {
      const auto& triangles = bucket[t * pages + g];
      if (triangles.empty()) continue;
      TexturedMesh::Group group = mesh.groups[g];
      group.first_index = index.size();
      group.index_count = triangles.size();
      index.insert(index.end(), triangles.begin(), triangles.end());
      tile.groups.push_back(group);
      groups.push_back(group);
      for (uint32_t v : triangles) {
        for (int k = 0; k < 3; ++k) {
          tlo[k] = std::min(tlo[k], mesh.position[3 * v + k]);
          thi[k] = std::max(thi[k], mesh.position[3 * v + k]);
        }
      }
    }
    if (tile.groups.empty()) continue;
    for (int k = 0; k < 3; ++k) tile.center[k] = (tlo[k] + thi[k]) / 2;
    tile.radius =
        std::sqrt((thi[0] - tlo[0]) * (thi[0] - tlo[0]) + (thi[1] - tlo[1]) * (thi[1] - tlo[1]) +
                  (thi[2] - tlo[2]) * (thi[2] - tlo[2])) /
        2;
    out.push_back(tile);
  }
  mesh.index = std::move(index);
  mesh.groups = std::move(groups);
  return out;
}

}  // namespace auv::view
