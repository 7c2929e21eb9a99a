#pragma once
// Binary PLY for points (with optional normals and colours), edges and triangles: what the
// stages write for viewing (MeshLab, CloudCompare, Open3D). Reading PLY is Open3D's job
// (open3d::io), in the stages that need it.

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace auv::recon::scene {

struct PlyData {
  std::vector<Eigen::Vector3d> positions;
  std::vector<Eigen::Vector3d> normals;              ///< empty or one per position
  std::vector<Eigen::Matrix<uint8_t, 3, 1>> colors;  ///< empty or one per position
  /// Per-vertex float properties after the colours (name, one value per position): scalar
  /// fields for CloudCompare and the like (e.g. a change's distance).
  std::vector<std::pair<std::string, std::vector<float>>> scalars;
  std::vector<std::array<uint32_t, 2>> edges;      ///< vertex index pairs
  std::vector<std::array<uint32_t, 3>> triangles;  ///< vertex index triples
};

/// Writes binary little-endian PLY through a temporary name. Throws std::invalid_argument for
/// inconsistent sizes or out-of-range indices, std::runtime_error when it cannot write.
void writePly(const std::filesystem::path& file, const PlyData& data);

/// Camera centres (coloured) and small view frusta as edges, for a viewer beside the points.
struct CameraGlyph {
  Eigen::Vector3d center;
  Eigen::Matrix3d rotation_cw;            ///< world -> camera
  double half_width, half_height, depth;  ///< frustum at `depth` in front of the centre
  Eigen::Matrix<uint8_t, 3, 1> color;
};
void appendCameraGlyph(const CameraGlyph& glyph, PlyData& data);

}  // namespace auv::recon::scene
