#include <meshoptimizer.h>
#include <open3d/geometry/Image.h>
#include <open3d/io/ImageIO.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <map>

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
      if (!mesh.uv.empty()) {
        out.uv.insert(out.uv.end(), mesh.uv.begin() + 2 * v, mesh.uv.begin() + 2 * v + 2);
      }
      if (!mesh.color.empty()) {
        out.color.insert(out.color.end(), mesh.color.begin() + 3 * v,
                         mesh.color.begin() + 3 * v + 3);
      }
    }
    out.index.push_back(remap[v]);
  }
  return out;
}

/// About half of `mesh`'s triangles, group by group (meshoptimizer's edge collapse).
MeshLevel halve(const TexturedMesh& mesh, unsigned options) {
  std::vector<uint32_t> index;
  std::vector<TexturedMesh::Group> groups;
  float worst = 0;
  for (const auto& group : mesh.groups) {
    const size_t target = std::max<size_t>(group.index_count / 2 / 3 * 3, 3);
    std::vector<uint32_t> out(group.index_count);
    float error = 0;
    // Target error 5 % of the extent: the triangle count decides, not the error bound.
    const size_t count = meshopt_simplify(
        out.data(), mesh.index.data() + group.first_index, group.index_count, mesh.position.data(),
        mesh.position.size() / 3, 3 * sizeof(float), target, 0.05f, options, &error);
    worst = std::max(worst, error);
    TexturedMesh::Group g = group;
    g.first_index = index.size();
    g.index_count = count;
    index.insert(index.end(), out.begin(), out.begin() + count);
    if (count > 0) groups.push_back(g);
  }
  return {compact(mesh, index, groups), worst};
}

/// An atlas page decoded once (RGB, 8 bits); empty when it cannot be read.
struct Page {
  open3d::geometry::Image image;
  bool ok = false;
  /// Bilinear at (u, v), OBJ convention (v up).
  void sample(float u, float v, float rgb[3]) const {
    const int w = image.width_, h = image.height_, c = image.num_of_channels_;
    const float x = std::clamp(u, 0.f, 1.f) * w - 0.5f,
                y = (1 - std::clamp(v, 0.f, 1.f)) * h - 0.5f;
    const int x0 = std::clamp(static_cast<int>(std::floor(x)), 0, w - 1);
    const int y0 = std::clamp(static_cast<int>(std::floor(y)), 0, h - 1);
    const int x1 = std::min(x0 + 1, w - 1), y1 = std::min(y0 + 1, h - 1);
    const float fx = std::clamp(x - x0, 0.f, 1.f), fy = std::clamp(y - y0, 0.f, 1.f);
    auto at = [&](int px, int py, int k) {
      return static_cast<float>(
          image.data_[(static_cast<size_t>(py) * w + px) * c + std::min(k, c - 1)]);
    };
    for (int k = 0; k < 3; ++k) {
      rgb[k] = (at(x0, y0, k) * (1 - fx) + at(x1, y0, k) * fx) * (1 - fy) +
               (at(x0, y1, k) * (1 - fx) + at(x1, y1, k) * fx) * fy;
    }
  }
};

Page readPage(const std::filesystem::path& file) {
  Page page;
  page.ok = open3d::io::ReadImage(file.string(), page.image) &&
            page.image.bytes_per_channel_ == 1 && page.image.width_ > 0 && page.image.height_ > 0;
  if (!page.ok) {
    std::cerr << "auv view: cannot decode texture " << file.string()
              << "; its coarse levels are drawn grey\n";
  }
  return page;
}

}  // namespace

TexturedMesh bakeVertexColours(const TexturedMesh& mesh) {
  // One vertex per position: the atlas's seams no longer split the surface.
  const size_t n = mesh.position.size() / 3;
  std::vector<uint32_t> remap(n);
  const size_t unique = meshopt_generateVertexRemap(remap.data(), nullptr, n, mesh.position.data(),
                                                    n, 3 * sizeof(float));
  TexturedMesh out;
  out.position.resize(3 * unique);
  meshopt_remapVertexBuffer(out.position.data(), mesh.position.data(), n, 3 * sizeof(float),
                            remap.data());
  out.index.reserve(mesh.index.size());
  for (uint32_t v : mesh.index) out.index.push_back(remap[v]);
  out.groups.push_back({0, out.index.size(), "vertex colours", {}});

  std::map<std::filesystem::path, Page> pages;
  std::vector<float> sum(3 * unique, 0.f);
  std::vector<uint32_t> samples(unique, 0);
  for (const auto& group : mesh.groups) {
    if (group.texture.empty()) continue;
    auto it = pages.find(group.texture);
    if (it == pages.end()) it = pages.emplace(group.texture, readPage(group.texture)).first;
    if (!it->second.ok) continue;
    for (size_t i = group.first_index; i < group.first_index + group.index_count; i += 3) {
      const uint32_t* corner = &mesh.index[i];
      float cu = 0, cv = 0;
      for (int k = 0; k < 3; ++k) {
        cu += mesh.uv[2 * corner[k]] / 3;
        cv += mesh.uv[2 * corner[k] + 1] / 3;
      }
      for (int k = 0; k < 3; ++k) {
        // A quarter of the way in: a patch's edge texels may bleed from its neighbours.
        const float u = 0.75f * mesh.uv[2 * corner[k]] + 0.25f * cu;
        const float v = 0.75f * mesh.uv[2 * corner[k] + 1] + 0.25f * cv;
        float rgb[3];
        it->second.sample(u, v, rgb);
        const uint32_t w = remap[corner[k]];
        for (int c = 0; c < 3; ++c) sum[3 * w + c] += rgb[c];
        ++samples[w];
      }
    }
  }
  out.color.resize(3 * unique);
  for (size_t v = 0; v < unique; ++v) {
    for (int c = 0; c < 3; ++c) {
      out.color[3 * v + c] =
          samples[v] ? static_cast<uint8_t>(std::lround(sum[3 * v + c] / samples[v])) : 160;
    }
  }
  return out;
}

std::vector<MeshLevel> buildLevels(const TexturedMesh& mesh, size_t min_triangles) {
  std::vector<MeshLevel> levels;
  levels.push_back({mesh, 0.f});
  const bool textured = std::any_of(mesh.groups.begin(), mesh.groups.end(),
                                    [](const auto& g) { return !g.texture.empty(); });
  while (levels.back().mesh.triangles() > min_triangles) {
    const TexturedMesh& previous = levels.back().mesh;
    const bool coloured = !previous.color.empty();
    MeshLevel next = halve(previous, coloured ? 0 : meshopt_SimplifyLockBorder);
    auto worthIt = [&] { return next.mesh.index.size() <= previous.index.size() * 8 / 10; };
    if (!worthIt() && textured && !coloured) {
      // The atlas pins the surface (a patch per face, or small charts: every vertex on a
      // seam): the coarser levels go on without it, coloured by it.
      next = halve(bakeVertexColours(previous), 0);
    }
    if (!worthIt()) break;  // no longer worth a level
    levels.push_back(std::move(next));
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
