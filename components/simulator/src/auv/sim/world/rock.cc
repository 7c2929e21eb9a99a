#include "auv/sim/world/rock.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>

namespace auv::sim {
namespace {

/// A unit icosphere: 12 vertices subdivided `levels` times (642 vertices at 3).
void icosphere(int levels, std::vector<Eigen::Vector3f>& vertices,
               std::vector<Eigen::Vector3i>& triangles) {
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  vertices = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
              {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  for (Eigen::Vector3f& v : vertices) v.normalize();
  triangles = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
               {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
               {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<int, int>, int> midpoints;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = midpoints.find(key);
      if (it != midpoints.end()) return it->second;
      vertices.push_back((vertices[a] + vertices[b]).normalized());
      return midpoints[key] = static_cast<int>(vertices.size()) - 1;
    };
    std::vector<Eigen::Vector3i> finer;
    for (const Eigen::Vector3i& f : triangles) {
      const int a = midpoint(f[0], f[1]), b = midpoint(f[1], f[2]), c = midpoint(f[2], f[0]);
      finer.insert(finer.end(), {{f[0], a, c}, {f[1], b, a}, {f[2], c, b}, {a, b, c}});
    }
    triangles = std::move(finer);
  }
}

size_t nearestTriangle(const Mesh& world, const Eigen::Vector3f& point) {
  size_t best = 0;
  float best_distance = std::numeric_limits<float>::max();
  for (size_t i = 0; i < world.triangles.size(); ++i) {
    const Eigen::Vector3i& t = world.triangles[i];
    const Eigen::Vector3f centre =
        (world.vertices[t[0]] + world.vertices[t[1]] + world.vertices[t[2]]) / 3.0f;
    const float d = (centre - point).squaredNorm();
    if (d < best_distance) best_distance = d, best = i;
  }
  return best;
}

/// Texture coordinates for the rock's triangles: each projected along its dominant normal axis
/// (rock frame, metres) at the texel size of `world`'s triangle `near`, around its texels.
std::vector<Eigen::Vector2f> rockUvs(const std::vector<Eigen::Vector3f>& local,
                                     const std::vector<Eigen::Vector3i>& triangles,
                                     const Mesh& world, size_t near) {
  const Eigen::Vector3i& t = world.triangles[near];
  const Eigen::Vector2f size(static_cast<float>(world.texture.cols),
                             static_cast<float>(world.texture.rows));
  Eigen::Vector2f px[3];
  for (int k = 0; k < 3; ++k) px[k] = world.triangle_uvs[3 * near + k].cwiseProduct(size);
  const float area_px = 0.5f * std::abs((px[1] - px[0]).x() * (px[2] - px[0]).y() -
                                        (px[1] - px[0]).y() * (px[2] - px[0]).x());
  const float area_m = 0.5f * (world.vertices[t[1]] - world.vertices[t[0]])
                                  .cross(world.vertices[t[2]] - world.vertices[t[0]])
                                  .norm();
  const float per_metre = area_m > 0.0f && area_px > 0.0f ? std::sqrt(area_px / area_m) : 100.0f;
  float reach = 0.0f;
  for (const Eigen::Vector3f& v : local) reach = std::max(reach, v.norm());
  reach *= per_metre;
  // Keep every coordinate inside the image.
  Eigen::Vector2f centre = (px[0] + px[1] + px[2]) / 3.0f;
  for (int a = 0; a < 2; ++a)
    centre[a] =
        size[a] > 2.0f * reach ? std::clamp(centre[a], reach, size[a] - reach) : size[a] / 2;
  std::vector<Eigen::Vector2f> uvs;
  uvs.reserve(3 * triangles.size());
  for (const Eigen::Vector3i& f : triangles) {
    const Eigen::Vector3f n =
        (local[f[1]] - local[f[0]]).cross(local[f[2]] - local[f[0]]).cwiseAbs();
    const int axis = n.x() >= n.y() && n.x() >= n.z() ? 0 : (n.y() >= n.z() ? 1 : 2);
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3f& v = local[f[k]];
      const Eigen::Vector2f planar = axis == 0   ? Eigen::Vector2f(v.y(), v.z())
                                     : axis == 1 ? Eigen::Vector2f(v.x(), v.z())
                                                 : Eigen::Vector2f(v.x(), v.y());
      uvs.push_back((centre + per_metre * planar).cwiseQuotient(size));
    }
  }
  return uvs;
}

}  // namespace

Mesh makeRock(const Eigen::Vector3d& base, const Eigen::Vector3d& size, double yaw_deg, int seed,
              const Mesh& world) {
  std::vector<Eigen::Vector3f> unit;
  std::vector<Eigen::Vector3i> triangles;
  icosphere(3, unit, triangles);
  // Lumps: a few smooth waves over the directions, +-15 % of the radius.
  std::mt19937 random(static_cast<uint32_t>(seed) * 2654435761u + 17u);
  std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
  struct Wave {
    Eigen::Vector3f direction;
    float frequency, phase, amplitude;
  };
  std::vector<Wave> waves;
  for (int w = 0; w < 5; ++w) {
    Eigen::Vector3f d(uniform(random) - 0.5f, uniform(random) - 0.5f, uniform(random) - 0.5f);
    waves.push_back({d.normalized(), 1.5f + 2.5f * uniform(random), 6.2832f * uniform(random),
                     0.03f + 0.03f * uniform(random)});
  }
  const Eigen::Vector3f radii = (0.5 * size).cast<float>();
  std::vector<Eigen::Vector3f> local;  // rock frame: x along its length, z down (NED)
  for (const Eigen::Vector3f& u : unit) {
    float lump = 1.0f;
    for (const Wave& w : waves)
      lump += w.amplitude * std::sin(w.frequency * w.direction.dot(u) + w.phase);
    local.push_back(lump * u.cwiseProduct(radii));
  }
  const Eigen::Matrix3f turn =
      Eigen::AngleAxisf(static_cast<float>(yaw_deg * M_PI / 180.0), Eigen::Vector3f::UnitZ())
          .toRotationMatrix();
  // Centre above the base (towards -z) so that 10 % of the height is below it.
  const Eigen::Vector3f centre =
      base.cast<float>() - Eigen::Vector3f(0.0f, 0.0f, 0.4f * static_cast<float>(size.z()));

  Mesh rock;
  rock.source = "rock (seed " + std::to_string(seed) + ")";
  for (const Eigen::Vector3f& v : local) rock.vertices.push_back(centre + turn * v);
  rock.triangles = triangles;
  // The icosphere's faces wind counter-clockwise seen from outside in a right-handed frame;
  // NED world positions keep that (rotation and translation only).
  if (world.hasTexture()) {
    rock.texture = world.texture;
    rock.triangle_uvs =
        rockUvs(local, triangles, world, nearestTriangle(world, base.cast<float>()));
  } else {
    Eigen::Vector3f colour(0.5f, 0.5f, 0.5f);
    if (world.hasVertexColors() && !world.triangles.empty())
      colour = world.vertex_colors[world.triangles[nearestTriangle(world, base.cast<float>())][0]];
    rock.vertex_colors.assign(rock.vertices.size(), colour);
  }
  return rock;
}

}  // namespace auv::sim
