#include "auv/recon/scene/ply.h"

#include <fstream>
#include <stdexcept>
#include <string>

#include "auv/recon/common/staged_output.h"

namespace fs = std::filesystem;

namespace auv::recon::scene {

namespace {
template <class T>
void put(std::ofstream& out, T value) {
  out.write(reinterpret_cast<const char*>(&value), sizeof value);  // x86/ARM: little endian
}
}  // namespace

void writePly(const fs::path& file, const PlyData& d) {
  const size_t n = d.positions.size();
  if (!d.normals.empty() && d.normals.size() != n) {
    throw std::invalid_argument(file.string() + ": " + std::to_string(d.normals.size()) +
                                " normals for " + std::to_string(n) + " points");
  }
  if (!d.colors.empty() && d.colors.size() != n) {
    throw std::invalid_argument(file.string() + ": " + std::to_string(d.colors.size()) +
                                " colours for " + std::to_string(n) + " points");
  }
  for (const auto& [name, values] : d.scalars) {
    if (values.size() != n) {
      throw std::invalid_argument(file.string() + ": " + std::to_string(values.size()) +
                                  " values of '" + name + "' for " + std::to_string(n) + " points");
    }
  }
  for (const auto& e : d.edges) {
    if (e[0] >= n || e[1] >= n) throw std::invalid_argument(file.string() + ": edge index");
  }
  for (const auto& t : d.triangles) {
    if (t[0] >= n || t[1] >= n || t[2] >= n) {
      throw std::invalid_argument(file.string() + ": triangle index");
    }
  }
  const fs::path temp = temporaryPathFor(file);
  std::ofstream out(temp, std::ios::binary);
  if (!out) throw std::runtime_error(file.string() + ": cannot write");
  out << "ply\nformat binary_little_endian 1.0\ncomment auv-inspect\n"
      << "element vertex " << n << "\nproperty float x\nproperty float y\nproperty float z\n";
  if (!d.normals.empty()) out << "property float nx\nproperty float ny\nproperty float nz\n";
  if (!d.colors.empty()) {
    out << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  }
  for (const auto& scalar : d.scalars) out << "property float " << scalar.first << "\n";
  if (!d.edges.empty()) {
    out << "element edge " << d.edges.size() << "\nproperty int vertex1\nproperty int vertex2\n";
  }
  if (!d.triangles.empty()) {
    out << "element face " << d.triangles.size() << "\nproperty list uchar int vertex_indices\n";
  }
  out << "end_header\n";
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) put(out, static_cast<float>(d.positions[i][k]));
    if (!d.normals.empty()) {
      for (int k = 0; k < 3; ++k) put(out, static_cast<float>(d.normals[i][k]));
    }
    if (!d.colors.empty()) {
      for (int k = 0; k < 3; ++k) put(out, d.colors[i][k]);
    }
    for (const auto& scalar : d.scalars) put(out, scalar.second[i]);
  }
  for (const auto& e : d.edges) {
    put(out, static_cast<int32_t>(e[0]));
    put(out, static_cast<int32_t>(e[1]));
  }
  for (const auto& t : d.triangles) {
    put(out, static_cast<uint8_t>(3));
    for (int k = 0; k < 3; ++k) put(out, static_cast<int32_t>(t[k]));
  }
  out.flush();
  if (!out) throw std::runtime_error(file.string() + ": cannot write");
  out.close();
  fs::rename(temp, file);
}

void appendCameraGlyph(const CameraGlyph& g, PlyData& data) {
  const uint32_t first = static_cast<uint32_t>(data.positions.size());
  const Eigen::Matrix3d to_world = g.rotation_cw.transpose();
  data.positions.push_back(g.center);
  for (const auto& [sx, sy] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}) {
    data.positions.push_back(
        g.center + to_world * Eigen::Vector3d(sx * g.half_width, sy * g.half_height, 1) * g.depth);
  }
  if (!data.colors.empty() || first == 0) data.colors.resize(data.positions.size(), g.color);
  if (!data.normals.empty()) data.normals.resize(data.positions.size(), Eigen::Vector3d::Zero());
  for (uint32_t k = 1; k <= 4; ++k) {
    data.edges.push_back({first, first + k});
    data.edges.push_back({first + k, first + (k % 4) + 1});
  }
}

}  // namespace auv::recon::scene
