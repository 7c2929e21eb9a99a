// Mesh files through Open3D (PLY with vertex colours, OBJ + MTL + texture). Open3D keeps OBJ
// texture coordinates as written (v up from the image's bottom) and the image flipped
// vertically in memory; Mesh uses image coordinates (v down from the top) and the image as
// stored, so both are converted here and nowhere else.
#include <open3d/geometry/TriangleMesh.h>
#include <open3d/io/TriangleMeshIO.h>
#include <open3d/utility/Logging.h>

#include <opencv2/imgproc.hpp>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "auv/config/mesh_file_check.h"
#include "auv/sim/common/yaml_section.h"
#include "auv/sim/world/mesh.h"

namespace auv::sim {
namespace {

namespace fs = std::filesystem;

std::string lowerExtension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

// Texture files an OBJ's material library names, for an error that names the missing file.
std::vector<std::string> objTextureFiles(const std::string& obj_path) {
  std::vector<std::string> files;
  std::ifstream obj(obj_path);
  std::string line;
  const fs::path dir = fs::path(obj_path).parent_path();
  while (std::getline(obj, line)) {
    std::istringstream words(line);
    std::string keyword, mtl;
    if (!(words >> keyword) || keyword != "mtllib" || !(words >> mtl)) continue;
    std::ifstream lib(dir / mtl);
    if (!lib) {
      files.push_back((dir / mtl).string() + " (material library)");
      continue;
    }
    std::string mline;
    while (std::getline(lib, mline)) {
      std::istringstream mwords(mline);
      std::string key, file;
      if (mwords >> key && key == "map_Kd" && mwords >> file)
        files.push_back((dir / file).string());
    }
  }
  return files;
}

cv::Mat toCvImage(const open3d::geometry::Image& image, const std::string& path) {
  if (image.bytes_per_channel_ != 1 ||
      (image.num_of_channels_ != 3 && image.num_of_channels_ != 4 && image.num_of_channels_ != 1)) {
    throw ConfigError(path + ": texture must be an 8-bit grey, RGB or RGBA image");
  }
  const int type = CV_8UC(image.num_of_channels_);
  cv::Mat wrapped(image.height_, image.width_, type, const_cast<uint8_t*>(image.data_.data()));
  cv::Mat bgr;
  if (image.num_of_channels_ == 1)
    cv::cvtColor(wrapped, bgr, cv::COLOR_GRAY2BGR);
  else if (image.num_of_channels_ == 3)
    cv::cvtColor(wrapped, bgr, cv::COLOR_RGB2BGR);
  else
    cv::cvtColor(wrapped, bgr, cv::COLOR_RGBA2BGR);
  cv::flip(bgr, bgr, 0);
  return bgr;
}

}  // namespace

Mesh loadMesh(const std::string& path) {
  const std::string ext = lowerExtension(path);
  if (ext != ".ply" && ext != ".obj") {
    throw ConfigError(path + ": unsupported mesh format '" + ext + "' (use .ply or .obj)");
  }
  if (!fs::is_regular_file(path)) throw ConfigError(path + ": no such mesh file");
  if (ext == ".ply") {
    const std::string problem = config::plyFileProblem(path, /*check_faces=*/true);
    if (!problem.empty()) throw ConfigError(path + ": cannot read the mesh: " + problem);
  }
  if (ext == ".obj") {
    const std::string problem = config::objFileProblem(path);
    if (!problem.empty()) throw ConfigError(path + ": cannot read the mesh: " + problem);
  }

  open3d::utility::SetVerbosityLevel(open3d::utility::VerbosityLevel::Error);
  open3d::geometry::TriangleMesh in;
  if (!open3d::io::ReadTriangleMesh(path, in) || in.triangles_.empty()) {
    throw ConfigError(path + ": cannot read a triangle mesh from the file (" +
                      std::to_string(in.vertices_.size()) + " vertices, " +
                      std::to_string(in.triangles_.size()) + " triangles read)");
  }

  Mesh mesh;
  mesh.source = path;
  mesh.vertices.reserve(in.vertices_.size());
  for (const Eigen::Vector3d& v : in.vertices_) mesh.vertices.push_back(v.cast<float>());
  for (const Eigen::Vector3i& t : in.triangles_) mesh.triangles.push_back(t);
  for (const Eigen::Vector3d& c : in.vertex_colors_) {
    mesh.vertex_colors.push_back(c.cast<float>().cwiseMax(0.0f).cwiseMin(1.0f));
  }

  if (!in.triangle_uvs_.empty()) {
    // One image for the whole mesh: collect the materials the triangles use.
    std::set<int> used(in.triangle_material_ids_.begin(), in.triangle_material_ids_.end());
    if (used.empty()) used.insert(0);
    const open3d::geometry::Image* texture = nullptr;
    for (int id : used) {
      if (id < 0 || id >= static_cast<int>(in.textures_.size()) || in.textures_[id].IsEmpty()) {
        continue;
      }
      if (texture) {
        throw ConfigError(path + ": uses " + std::to_string(used.size()) +
                          " textures; the simulator needs one texture per mesh (bake the "
                          "materials into one atlas)");
      }
      texture = &in.textures_[id];
    }
    if (!texture) {
      std::string named;
      for (const std::string& f : objTextureFiles(path)) {
        if (!fs::is_regular_file(f)) named += (named.empty() ? "" : ", ") + f;
      }
      throw ConfigError(
          path + ": has texture coordinates but its texture could not be read" +
          (named.empty() ? std::string(" (no map_Kd in its .mtl)") : " (missing: " + named + ")"));
    }
    mesh.texture = toCvImage(*texture, path);
    mesh.triangle_uvs.reserve(in.triangle_uvs_.size());
    for (const Eigen::Vector2d& uv : in.triangle_uvs_) {
      mesh.triangle_uvs.emplace_back(static_cast<float>(uv.x()), static_cast<float>(1.0 - uv.y()));
    }
  }
  return mesh;
}

void saveMesh(const Mesh& mesh, const std::string& path) {
  const std::string ext = lowerExtension(path);
  if (ext != ".ply" && ext != ".obj") {
    throw ConfigError(path + ": unsupported mesh format '" + ext + "' (use .ply or .obj)");
  }
  if (ext == ".ply" && mesh.hasTexture()) {
    throw ConfigError(path + ": a textured mesh must be written as .obj (PLY keeps no texture)");
  }
  open3d::geometry::TriangleMesh out;
  out.vertices_.reserve(mesh.vertices.size());
  for (const Eigen::Vector3f& v : mesh.vertices) out.vertices_.push_back(v.cast<double>());
  out.triangles_ = mesh.triangles;
  for (const Eigen::Vector3f& c : mesh.vertex_colors)
    out.vertex_colors_.push_back(c.cast<double>());
  if (mesh.hasTexture()) {
    for (const Eigen::Vector2f& uv : mesh.triangle_uvs) {
      out.triangle_uvs_.emplace_back(uv.x(), 1.0 - uv.y());
    }
    cv::Mat rgb;
    cv::cvtColor(mesh.texture, rgb, cv::COLOR_BGR2RGB);
    cv::flip(rgb, rgb, 0);
    open3d::geometry::Image image;
    image.Prepare(rgb.cols, rgb.rows, 3, 1);
    for (int r = 0; r < rgb.rows; ++r) {
      std::memcpy(image.data_.data() + static_cast<size_t>(r) * rgb.cols * 3, rgb.ptr(r),
                  static_cast<size_t>(rgb.cols) * 3);
    }
    out.textures_.push_back(std::move(image));
    out.triangle_material_ids_.assign(mesh.triangles.size(), 0);
  }
  open3d::utility::SetVerbosityLevel(open3d::utility::VerbosityLevel::Error);
  const bool ascii = false;
  if (!open3d::io::WriteTriangleMesh(path, out, ascii, false, /*normals=*/false,
                                     /*colors=*/!mesh.vertex_colors.empty(),
                                     /*uvs=*/mesh.hasTexture())) {
    throw ConfigError(path + ": cannot write the mesh");
  }
}

}  // namespace auv::sim
