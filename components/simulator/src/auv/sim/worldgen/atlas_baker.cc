#include "auv/sim/worldgen/atlas_baker.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>
#include <string>

#include "auv/sim/common/yaml_section.h"

// ThreadSanitizer cannot see OpenCV's thread pool (TBB, not instrumented) hand the patches to
// its workers and the baked texture back, and took the workers' reads for races; under TSan the
// loop says so itself (docs/reliability.md, "Sanitizers").
#if defined(__has_feature)
#if __has_feature(thread_sanitizer)
extern "C" void __tsan_acquire(void* addr);
extern "C" void __tsan_release(void* addr);
#define AUV_HAND_OVER_ACQUIRE(object) __tsan_acquire(object)
#define AUV_HAND_OVER_RELEASE(object) __tsan_release(object)
#endif
#endif
#ifndef AUV_HAND_OVER_ACQUIRE
#define AUV_HAND_OVER_ACQUIRE(object) (void)(object)
#define AUV_HAND_OVER_RELEASE(object) (void)(object)
#endif

namespace auv::sim::worldgen {
namespace {

using Eigen::Vector3f;

// A block of quads [r0, r1) x [c0, c1) of one grid and its atlas cell. xs/ys are the cell-local
// pixel coordinates of its point columns/rows (texel centres at i + 0.5), spaced in proportion
// to the 3D lengths so the density is the same everywhere in the cell.
struct Patch {
  int grid = 0;
  int r0 = 0, r1 = 0, c0 = 0, c1 = 0;
  std::vector<float> xs, ys;
  int width = 0, height = 0;  // px, with padding
  int x = 0, y = 0;           // px, cell origin in the atlas
  float texel = 0.0f;         // m
};

int pointCol(const SurfaceGrid& grid, int c) { return grid.wrap ? c % grid.cols : c; }

float colLength(const SurfaceGrid& grid, int r, int c) {
  return (grid.at(r, pointCol(grid, c + 1)) - grid.at(r, c)).norm();
}
float rowLength(const SurfaceGrid& grid, int r, int c) {
  return (grid.at(r + 1, pointCol(grid, c)) - grid.at(r, pointCol(grid, c))).norm();
}

// Splits [0, lengths.size()) into runs whose summed length stays within `max_span` (m) and
// whose `groups` entries (if given) are all equal.
std::vector<std::pair<int, int>> splitRuns(const std::vector<float>& lengths, float max_span,
                                           const std::vector<uint8_t>* groups = nullptr) {
  std::vector<std::pair<int, int>> runs;
  int start = 0;
  float sum = 0.0f;
  for (int i = 0; i < static_cast<int>(lengths.size()); ++i) {
    const bool new_group = groups && i > start && (*groups)[i] != (*groups)[i - 1];
    if (i > start && (new_group || sum + lengths[i] > max_span)) {
      runs.emplace_back(start, i);
      start = i;
      sum = 0.0f;
    }
    sum += lengths[i];
  }
  if (start < static_cast<int>(lengths.size())) runs.emplace_back(start, lengths.size());
  return runs;
}

// Pixel coordinates of the lines between runs of `lengths`; returns the cell size.
int placeLines(const std::vector<float>& lengths, float texel, int padding,
               std::vector<float>& lines) {
  const float total = std::accumulate(lengths.begin(), lengths.end(), 0.0f);
  const int inner = std::max(1, static_cast<int>(std::ceil(total / texel)));
  lines.assign(lengths.size() + 1, 0.0f);
  float cumulative = 0.0f;
  for (size_t i = 0; i <= lengths.size(); ++i) {
    const float fraction = total > 0.0f
                               ? cumulative / total
                               : static_cast<float>(i) / static_cast<float>(lengths.size());
    lines[i] = static_cast<float>(padding) + 0.5f + fraction * static_cast<float>(inner);
    if (i < lengths.size()) cumulative += lengths[i];
  }
  return inner + 1 + 2 * padding;
}

std::vector<Patch> layoutPatches(const std::vector<SurfaceGrid>& grids, float scale,
                                 const AtlasOptions& options) {
  std::vector<Patch> patches;
  const int usable = options.max_cell_size - 2 * options.padding - 1;
  for (int g = 0; g < static_cast<int>(grids.size()); ++g) {
    const SurfaceGrid& grid = grids[g];
    std::vector<float> row_lengths(grid.quadRows(), 0.0f);
    std::vector<uint8_t> dry(grid.quadRows(), 1);  // quad row wholly above the surface
    for (int r = 0; r < grid.quadRows(); ++r) {
      for (int c = 0; c < grid.cols; ++c) {
        row_lengths[r] = std::max(row_lengths[r], rowLength(grid, r, c));
        if (grid.at(r, c).z() <= 0.0f || grid.at(r + 1, c).z() <= 0.0f) dry[r] = 0;
      }
    }
    const float wet_texel = grid.texel_size * scale;
    for (const auto& [r0, r1] :
         splitRuns(row_lengths, wet_texel * static_cast<float>(usable), &dry)) {
      const float texel = dry[r0] ? wet_texel * options.dry_texel_factor : wet_texel;
      const float max_span = texel * static_cast<float>(usable);
      std::vector<float> col_lengths(grid.quadCols(), 0.0f);
      for (int c = 0; c < grid.quadCols(); ++c) {
        for (int r = r0; r <= r1; ++r)
          col_lengths[c] = std::max(col_lengths[c], colLength(grid, r, c));
      }
      for (const auto& [c0, c1] : splitRuns(col_lengths, max_span)) {
        bool any = false;
        for (int r = r0; r < r1 && !any; ++r) {
          for (int c = c0; c < c1 && !any; ++c) any = grid.quadEnabled(r, c);
        }
        if (!any) continue;
        Patch patch;
        patch.grid = g;
        patch.r0 = r0, patch.r1 = r1, patch.c0 = c0, patch.c1 = c1;
        const std::vector<float> widths(col_lengths.begin() + c0, col_lengths.begin() + c1);
        std::vector<float> heights(r1 - r0, 0.0f);
        for (int r = r0; r < r1; ++r) {
          for (int c = c0; c <= c1; ++c)
            heights[r - r0] = std::max(heights[r - r0], rowLength(grid, r, c));
        }
        patch.texel = texel;
        patch.width = placeLines(widths, texel, options.padding, patch.xs);
        patch.height = placeLines(heights, texel, options.padding, patch.ys);
        patches.push_back(std::move(patch));
      }
    }
  }
  return patches;
}

// Shelf packing, tallest cells first; returns the atlas height.
int packPatches(std::vector<Patch>& patches, int atlas_width) {
  std::vector<size_t> order(patches.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return patches[a].height != patches[b].height ? patches[a].height > patches[b].height
                                                  : patches[a].width > patches[b].width;
  });
  int x = 0, y = 0, shelf = 0;
  for (size_t i : order) {
    Patch& p = patches[i];
    if (x + p.width > atlas_width) {
      x = 0;
      y += shelf;
      shelf = 0;
    }
    p.x = x;
    p.y = y;
    x += p.width;
    shelf = std::max(shelf, p.height);
  }
  return y + shelf;
}

// For each pixel of a cell along one axis: the quad index and the fraction within it
// (extrapolated into the padding).
void pixelToQuad(const std::vector<float>& lines, int size, std::vector<int>& quad,
                 std::vector<float>& fraction) {
  const int quads = static_cast<int>(lines.size()) - 1;
  quad.resize(size);
  fraction.resize(size);
  int k = 0;
  for (int i = 0; i < size; ++i) {
    const float centre = static_cast<float>(i) + 0.5f;
    while (k < quads - 1 && centre > lines[k + 1]) ++k;
    const float span = lines[k + 1] - lines[k];
    quad[i] = k;
    fraction[i] = span > 1e-6f ? (centre - lines[k]) / span : 0.0f;
  }
}

// The point of quad (a, b, e, d) at fractions (fu, fv), on the triangle the mesh uses there.
template <typename V>
V onQuad(const V& a, const V& b, const V& e, const V& d, float fu, float fv) {
  if (fu >= fv) return a + (fu - fv) * (b - a) + fv * (e - a);
  return a + fu * (e - a) + (fv - fu) * (d - a);
}

void bakePatch(const Patch& patch, const SurfaceGrid& grid, const MaterialShader& shader,
               float texel, int coarse_step, cv::Mat& texture) {
  std::vector<int> col_quad, row_quad;
  std::vector<float> col_frac, row_frac;
  pixelToQuad(patch.xs, patch.width, col_quad, col_frac);
  pixelToQuad(patch.ys, patch.height, row_quad, row_frac);

  auto surfaceAt = [&](int i, int j, Vector3f& point, Vector3f& normal) {
    const int r = patch.r0 + row_quad[j];
    const int c = patch.c0 + col_quad[i];
    const int c1 = pointCol(grid, c + 1);
    const float fu = col_frac[i], fv = row_frac[j];
    point = onQuad(grid.at(r, c), grid.at(r, c1), grid.at(r + 1, c1), grid.at(r + 1, c), fu, fv);
    const auto n = [&](int rr, int cc) {
      return grid.normals[static_cast<size_t>(rr) * grid.cols + cc];
    };
    normal = onQuad(n(r, c), n(r, c1), n(r + 1, c1), n(r + 1, c), fu, fv);
    const float length = normal.norm();
    normal = length > 1e-6f ? Vector3f(normal / length) : Vector3f::UnitZ();
  };

  // Slow fields on a coarse lattice of texels, interpolated bilinearly below.
  const int step = coarse_step;
  const int coarse_w = (patch.width - 1) / step + 2, coarse_h = (patch.height - 1) / step + 2;
  std::vector<CoarseFields> coarse(static_cast<size_t>(coarse_w) * coarse_h);
  for (int gj = 0; gj < coarse_h; ++gj) {
    for (int gi = 0; gi < coarse_w; ++gi) {
      Vector3f point, normal;
      surfaceAt(std::min(gi * step, patch.width - 1), std::min(gj * step, patch.height - 1), point,
                normal);
      coarse[static_cast<size_t>(gj) * coarse_w + gi] = shader.coarse(grid.material, point, normal);
    }
  }
  // Weights are exact only on the lattice; the last lattice column/row repeats the edge texel.
  for (int j = 0; j < patch.height; ++j) {
    const int gj = j / step;
    const float tj = static_cast<float>(j - gj * step) / static_cast<float>(step);
    auto* pixels = texture.ptr<cv::Vec3b>(patch.y + j) + patch.x;
    for (int i = 0; i < patch.width; ++i) {
      const int gi = i / step;
      const float ti = static_cast<float>(i - gi * step) / static_cast<float>(step);
      const CoarseFields& f00 = coarse[static_cast<size_t>(gj) * coarse_w + gi];
      const CoarseFields& f10 = coarse[static_cast<size_t>(gj) * coarse_w + gi + 1];
      const CoarseFields& f01 = coarse[static_cast<size_t>(gj + 1) * coarse_w + gi];
      const CoarseFields& f11 = coarse[static_cast<size_t>(gj + 1) * coarse_w + gi + 1];
      CoarseFields fields;
      for (int k = 0; k < CoarseFields::kCount; ++k) {
        const float top = f00.value[k] + ti * (f10.value[k] - f00.value[k]);
        const float bottom = f01.value[k] + ti * (f11.value[k] - f01.value[k]);
        fields.value[k] = top + tj * (bottom - top);
      }
      Vector3f point, normal;
      surfaceAt(i, j, point, normal);
      const Vector3f rgb = shader.shadeFine(grid.material, point, normal, texel, fields);
      pixels[i] = cv::Vec3b(static_cast<uchar>(rgb.z() * 255.0f + 0.5f),
                            static_cast<uchar>(rgb.y() * 255.0f + 0.5f),
                            static_cast<uchar>(rgb.x() * 255.0f + 0.5f));
    }
  }
}

int roundUp(int value, int multiple) { return (value + multiple - 1) / multiple * multiple; }

}  // namespace

void AtlasOptions::check() const {
  auto fail = [](const std::string& field, const std::string& what) {
    throw ConfigError("atlas." + field + ": " + what);
  };
  if (max_texture_size < 64 || max_texture_size > 16384)
    fail("max_texture_size", "expected 64..16384 px, got " + std::to_string(max_texture_size));
  if (max_cell_size < 8 || max_cell_size > max_texture_size)
    fail("max_cell_size", "expected 8..max_texture_size px, got " + std::to_string(max_cell_size));
  if (padding < 0 || 4 * padding >= max_cell_size)
    fail("padding", "expected 0..max_cell_size/4 px, got " + std::to_string(padding));
  if (!(dry_texel_factor >= 1.0f && dry_texel_factor <= 100.0f))
    fail("dry_texel_factor", "expected 1..100, got " + std::to_string(dry_texel_factor));
  if (coarse_step < 1 || coarse_step > 16)
    fail("coarse_step", "expected 1..16 px, got " + std::to_string(coarse_step));
}

Mesh bakeTexturedMesh(const std::vector<SurfaceGrid>& grids, const AtlasOptions& options,
                      AtlasReport* report) {
  options.check();
  for (const SurfaceGrid& grid : grids) {
    if (grid.rows < 2 || grid.cols < 2 ||
        grid.points.size() != static_cast<size_t>(grid.rows) * grid.cols ||
        grid.normals.size() != grid.points.size() || !(grid.texel_size > 0.0f)) {
      throw ConfigError("worldgen: inconsistent surface grid (" + std::to_string(grid.rows) + "x" +
                        std::to_string(grid.cols) + ", " + materialName(grid.material) + ")");
    }
  }

  // Texel sizes as asked, grown uniformly until every cell fits in the atlas.
  const double max_side = options.max_texture_size;
  float scale = 1.0f;
  std::vector<Patch> patches = layoutPatches(grids, scale, options);
  auto cellArea = [&]() {
    double area = 0.0;
    for (const Patch& p : patches) area += static_cast<double>(p.width) * p.height;
    return area;
  };
  if (cellArea() > 0.9 * max_side * max_side) {
    scale = static_cast<float>(std::sqrt(cellArea() / (0.9 * max_side * max_side)));
    patches = layoutPatches(grids, scale, options);
  }
  int width = 0, height = 0;
  for (;;) {
    int widest = 0;
    for (const Patch& p : patches) widest = std::max(widest, p.width);
    width = std::min(options.max_texture_size,
                     std::max(widest, roundUp(static_cast<int>(std::sqrt(cellArea() * 1.04)), 16)));
    height = roundUp(std::max(packPatches(patches, width), 1), 4);
    if (height <= options.max_texture_size) break;
    scale *= std::max(1.02f, static_cast<float>(std::sqrt(height / max_side)));
    patches = layoutPatches(grids, scale, options);
  }

  Mesh mesh;
  mesh.texture = cv::Mat(height, width, CV_8UC3, cv::Scalar(110, 120, 120));
  const MaterialShader shader(options.seed);
  AUV_HAND_OVER_RELEASE(&patches);
  cv::parallel_for_(cv::Range(0, static_cast<int>(patches.size())), [&](const cv::Range& range) {
    AUV_HAND_OVER_ACQUIRE(&patches);
    for (int i = range.start; i < range.end; ++i) {
      const Patch& patch = patches[i];
      bakePatch(patch, grids[patch.grid], shader, patch.texel, options.coarse_step, mesh.texture);
    }
    AUV_HAND_OVER_RELEASE(&patches);
  });
  AUV_HAND_OVER_ACQUIRE(&patches);

  // Triangles with the texture coordinates of their patch; vertices shared within a grid.
  std::vector<size_t> grid_base(grids.size() + 1, 0);
  for (size_t g = 0; g < grids.size(); ++g)
    grid_base[g + 1] = grid_base[g] + grids[g].points.size();
  std::vector<int> remap(grid_base.back(), -1);
  auto vertexIndex = [&](int g, int r, int c) {
    const size_t key = grid_base[g] + static_cast<size_t>(r) * grids[g].cols + c;
    if (remap[key] < 0) {
      remap[key] = static_cast<int>(mesh.vertices.size());
      mesh.vertices.push_back(grids[g].at(r, c));
    }
    return remap[key];
  };
  for (const Patch& patch : patches) {
    const SurfaceGrid& grid = grids[patch.grid];
    for (int r = patch.r0; r < patch.r1; ++r) {
      for (int c = patch.c0; c < patch.c1; ++c) {
        if (!grid.quadEnabled(r, c)) continue;
        const int c1 = pointCol(grid, c + 1);
        const float u0 = (patch.x + patch.xs[c - patch.c0]) / width;
        const float u1 = (patch.x + patch.xs[c + 1 - patch.c0]) / width;
        const float v0 = (patch.y + patch.ys[r - patch.r0]) / height;
        const float v1 = (patch.y + patch.ys[r + 1 - patch.r0]) / height;
        const int corners[4][2] = {{r, c}, {r, c1}, {r + 1, c1}, {r + 1, c}};
        const Eigen::Vector2f uvs[4] = {{u0, v0}, {u1, v0}, {u1, v1}, {u0, v1}};
        for (const auto& tri : {std::array<int, 3>{0, 1, 2}, std::array<int, 3>{0, 2, 3}}) {
          const Vector3f& a = grid.at(corners[tri[0]][0], corners[tri[0]][1]);
          const Vector3f& b = grid.at(corners[tri[1]][0], corners[tri[1]][1]);
          const Vector3f& d = grid.at(corners[tri[2]][0], corners[tri[2]][1]);
          if ((b - a).cross(d - a).squaredNorm() < 1e-14f) continue;  // collapsed crest
          Eigen::Vector3i triangle;
          for (int k = 0; k < 3; ++k) {
            triangle[k] = vertexIndex(patch.grid, corners[tri[k]][0], corners[tri[k]][1]);
            mesh.triangle_uvs.push_back(uvs[tri[k]]);
          }
          mesh.triangles.push_back(triangle);
        }
      }
    }
  }

  if (report) {
    report->texture_width = width;
    report->texture_height = height;
    report->texel_scale = scale;
    report->cells = patches.size();
    report->fill = cellArea() / (static_cast<double>(width) * height);
  }
  return mesh;
}

}  // namespace auv::sim::worldgen
