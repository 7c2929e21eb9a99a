#pragma once
// A world is a triangle mesh in the world frame (NED, metres) with either a texture (per-corner
// texture coordinates + one image) or per-vertex colours. Any mesh a user brings is loaded
// from PLY or OBJ and validated before the simulator uses it.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace auv::sim {

struct Mesh {
  std::vector<Eigen::Vector3f> vertices;   ///< m
  std::vector<Eigen::Vector3i> triangles;  ///< vertex indices, counter-clockwise seen from outside
  std::vector<Eigen::Vector3f> vertex_colors;  ///< sRGB in [0, 1], one per vertex, or empty
  std::vector<Eigen::Vector2f> triangle_uvs;   ///< 3 per triangle (corner order), or empty;
                                               ///< u right, v down from the image's top-left
  cv::Mat texture;                             ///< CV_8UC3 BGR (sRGB), empty when untextured
  std::string source;                          ///< file it came from, for messages

  bool hasTexture() const { return !texture.empty() && !triangle_uvs.empty(); }
  bool hasVertexColors() const { return !vertex_colors.empty(); }
};

/// What validation found and repaired.
struct MeshReport {
  size_t triangles = 0;           ///< kept
  size_t removed_degenerate = 0;  ///< zero-area or repeated-vertex triangles dropped
  Eigen::AlignedBox3f bounds;
};

/// Reads a PLY (vertex colours) or OBJ (+ MTL + texture image) file. Throws ConfigError naming
/// the file when it cannot be read, has no triangles, or references a texture that is missing.
Mesh loadMesh(const std::string& path);

/// Writes PLY (vertex colours) or OBJ (+ MTL + PNG texture next to it), chosen by extension.
void saveMesh(const Mesh& mesh, const std::string& path);

/// Checks a mesh before use: non-empty, finite vertices, indices in range, colour or texture
/// present and sized consistently. Drops degenerate triangles (reported); throws ConfigError
/// naming `mesh.source` when nothing usable is left or data is inconsistent.
MeshReport validateMesh(Mesh& mesh);

/// Applies a rigid transform (with optional uniform scale folded into `transform`).
void transformMesh(Mesh& mesh, const Eigen::Affine3f& transform);

/// Appends `other` to `mesh` (both untextured, or both textured with the same image).
void appendMesh(Mesh& mesh, const Mesh& other);

Eigen::AlignedBox3f meshBounds(const Mesh& mesh);

}  // namespace auv::sim
