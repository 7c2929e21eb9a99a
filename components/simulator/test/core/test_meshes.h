#pragma once
// Small analytic meshes for tests.
#include "auv/sim/world/mesh.h"

namespace auv::sim::test {

/// Axis-aligned square in the plane x = `x`, spanning y, z in [-half, half], one colour.
inline Mesh wallAtX(float x, float half, const Eigen::Vector3f& color = {0.5f, 0.5f, 0.5f}) {
  Mesh m;
  m.vertices = {{x, -half, -half}, {x, half, -half}, {x, half, half}, {x, -half, half}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  m.vertex_colors.assign(4, color);
  m.source = "wall";
  return m;
}

/// Closed axis-aligned box [min, max], one colour.
inline Mesh box(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi,
                const Eigen::Vector3f& color = {0.5f, 0.5f, 0.5f}) {
  Mesh m;
  for (int i = 0; i < 8; ++i) {
    m.vertices.emplace_back((i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(),
                            (i & 4) ? hi.z() : lo.z());
  }
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces) {
    m.triangles.emplace_back(f[0], f[1], f[2]);
    m.triangles.emplace_back(f[0], f[2], f[3]);
  }
  m.vertex_colors.assign(8, color);
  m.source = "box";
  return m;
}

/// UV sphere of `radius` at `center` (for curved-surface distance checks).
inline Mesh sphere(const Eigen::Vector3f& center, float radius, int rings = 64,
                   int segments = 128) {
  Mesh m;
  for (int r = 0; r <= rings; ++r) {
    const float theta = static_cast<float>(M_PI) * r / rings;
    for (int s = 0; s < segments; ++s) {
      const float phi = 2.0f * static_cast<float>(M_PI) * s / segments;
      m.vertices.push_back(center + radius * Eigen::Vector3f(std::sin(theta) * std::cos(phi),
                                                             std::sin(theta) * std::sin(phi),
                                                             std::cos(theta)));
    }
  }
  for (int r = 0; r < rings; ++r) {
    for (int s = 0; s < segments; ++s) {
      const int a = r * segments + s, b = r * segments + (s + 1) % segments;
      const int c = a + segments, d = b + segments;
      m.triangles.emplace_back(a, c, b);
      m.triangles.emplace_back(b, c, d);
    }
  }
  m.vertex_colors.assign(m.vertices.size(), Eigen::Vector3f(0.5f, 0.5f, 0.5f));
  m.source = "sphere";
  return m;
}

}  // namespace auv::sim::test
