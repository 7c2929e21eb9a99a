#include "auv/sim/world/mesh.h"

#include <cmath>

#include "auv/sim/common/yaml_section.h"

namespace auv::sim {

Eigen::AlignedBox3f meshBounds(const Mesh& mesh) {
  Eigen::AlignedBox3f box;
  for (const Eigen::Vector3f& v : mesh.vertices) box.extend(v);
  return box;
}

MeshReport validateMesh(Mesh& mesh) {
  const std::string& name = mesh.source.empty() ? std::string("mesh") : mesh.source;
  if (mesh.vertices.empty() || mesh.triangles.empty()) {
    throw ConfigError(name + ": the mesh is empty (" + std::to_string(mesh.vertices.size()) +
                      " vertices, " + std::to_string(mesh.triangles.size()) + " triangles)");
  }
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    if (!mesh.vertices[i].allFinite()) {
      throw ConfigError(name + ": vertex " + std::to_string(i) + " is not finite");
    }
  }
  const bool textured = !mesh.triangle_uvs.empty();
  if (textured && mesh.triangle_uvs.size() != 3 * mesh.triangles.size()) {
    throw ConfigError(name + ": " + std::to_string(mesh.triangle_uvs.size()) +
                      " texture coordinates for " + std::to_string(mesh.triangles.size()) +
                      " triangles (expected 3 per triangle)");
  }
  if (textured && mesh.texture.empty()) {
    throw ConfigError(name + ": has texture coordinates but no texture image");
  }
  if (!mesh.texture.empty() && mesh.texture.type() != CV_8UC3) {
    throw ConfigError(name + ": the texture must be an 8-bit colour image");
  }
  if (!mesh.vertex_colors.empty() && mesh.vertex_colors.size() != mesh.vertices.size()) {
    throw ConfigError(name + ": " + std::to_string(mesh.vertex_colors.size()) +
                      " vertex colours for " + std::to_string(mesh.vertices.size()) + " vertices");
  }
  if (!mesh.hasTexture() && !mesh.hasVertexColors()) {
    throw ConfigError(name +
                      ": has neither a texture nor vertex colours (set world.default_color in "
                      "the scenario to render it in one colour)");
  }

  // Degenerate triangles (repeated vertices, zero area) are common in real meshes and
  // harmless once removed; an index out of range means the file is corrupt.
  MeshReport report;
  std::vector<Eigen::Vector3i> kept;
  std::vector<Eigen::Vector2f> kept_uvs;
  kept.reserve(mesh.triangles.size());
  const int n = static_cast<int>(mesh.vertices.size());
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Eigen::Vector3i& tri = mesh.triangles[t];
    for (int k = 0; k < 3; ++k) {
      if (tri[k] < 0 || tri[k] >= n) {
        throw ConfigError(name + ": triangle " + std::to_string(t) + " refers to vertex " +
                          std::to_string(tri[k]) + " of " + std::to_string(n));
      }
    }
    const Eigen::Vector3f e1 = mesh.vertices[tri[1]] - mesh.vertices[tri[0]];
    const Eigen::Vector3f e2 = mesh.vertices[tri[2]] - mesh.vertices[tri[0]];
    const float scale = std::max(e1.squaredNorm(), e2.squaredNorm());
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] ||
        e1.cross(e2).squaredNorm() <= 1e-12f * scale * scale || scale == 0.0f) {
      ++report.removed_degenerate;
      continue;
    }
    kept.push_back(tri);
    if (textured) {
      for (int k = 0; k < 3; ++k) kept_uvs.push_back(mesh.triangle_uvs[3 * t + k]);
    }
  }
  if (kept.empty()) {
    throw ConfigError(name + ": all " + std::to_string(mesh.triangles.size()) +
                      " triangles are degenerate (zero area)");
  }
  mesh.triangles = std::move(kept);
  if (textured) mesh.triangle_uvs = std::move(kept_uvs);
  report.triangles = mesh.triangles.size();
  report.bounds = meshBounds(mesh);
  return report;
}

void transformMesh(Mesh& mesh, const Eigen::Affine3f& transform) {
  for (Eigen::Vector3f& v : mesh.vertices) v = transform * v;
  // A mirroring transform flips the winding; keep triangles counter-clockwise from outside.
  if (transform.linear().determinant() < 0) {
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      std::swap(mesh.triangles[t][1], mesh.triangles[t][2]);
      if (!mesh.triangle_uvs.empty())
        std::swap(mesh.triangle_uvs[3 * t + 1], mesh.triangle_uvs[3 * t + 2]);
    }
  }
}

void appendMesh(Mesh& mesh, const Mesh& other) {
  if (mesh.hasTexture() != other.hasTexture() && !mesh.vertices.empty()) {
    throw ConfigError("appendMesh: cannot mix textured and untextured meshes");
  }
  const int offset = static_cast<int>(mesh.vertices.size());
  mesh.vertices.insert(mesh.vertices.end(), other.vertices.begin(), other.vertices.end());
  mesh.vertex_colors.insert(mesh.vertex_colors.end(), other.vertex_colors.begin(),
                            other.vertex_colors.end());
  for (const Eigen::Vector3i& t : other.triangles) {
    mesh.triangles.push_back(t + Eigen::Vector3i::Constant(offset));
  }
  mesh.triangle_uvs.insert(mesh.triangle_uvs.end(), other.triangle_uvs.begin(),
                           other.triangle_uvs.end());
  if (mesh.texture.empty()) mesh.texture = other.texture;
}

}  // namespace auv::sim
