#include "auv/recon/scene/mesh_io.h"

#include <open3d/geometry/PointCloud.h>
#include <open3d/geometry/TriangleMesh.h>
#include <open3d/io/PointCloudIO.h>
#include <open3d/io/TriangleMeshIO.h>

#include "auv/config/mesh_file_check.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/survey.h"
#include "auv/recon/scene/ply.h"

namespace fs = std::filesystem;
namespace o3d = open3d::geometry;

namespace auv::recon::scene {

namespace {

/// What Open3D must not be given (auv/config/mesh_file_check.h) for the files it reads as PLY or
/// OBJ.
std::string readProblem(const fs::path& file, bool faces) {
  std::string extension = file.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (extension == ".ply") return config::plyFileProblem(file.string(), faces);
  return extension == ".obj" ? config::objFileProblem(file.string()) : "";
}

// Open3D's readers, for a file readProblem() passed.
bool openPointCloud(const fs::path& file, o3d::PointCloud& cloud, bool drop_non_finite) {
  open3d::io::ReadPointCloudOption options;
  options.remove_nan_points = drop_non_finite;
  options.remove_infinite_points = drop_non_finite;
  return open3d::io::ReadPointCloud(file.string(), cloud, options);
}

bool openTriangleMesh(const fs::path& file, o3d::TriangleMesh& mesh) {
  open3d::io::ReadTriangleMeshOptions options;
  options.enable_post_processing = false;
  options.print_progress = false;
  return open3d::io::ReadTriangleMesh(file.string(), mesh, options);
}

}  // namespace

bool readPointCloud(const fs::path& file, o3d::PointCloud& cloud, bool drop_non_finite) {
  return readProblem(file, false).empty() && openPointCloud(file, cloud, drop_non_finite);
}

bool readTriangleMesh(const fs::path& file, o3d::TriangleMesh& mesh) {
  return readProblem(file, true).empty() && openTriangleMesh(file, mesh);
}

o3d::PointCloud readCloud(const fs::path& file, const std::string& stage,
                          const std::string& producer) {
  Survey::requireExists(file, stage, producer);
  if (const std::string problem = readProblem(file, false); !problem.empty()) {
    throw StageError(stage, file.string() + ": cannot read the point cloud: " + problem);
  }
  o3d::PointCloud cloud;
  if (!openPointCloud(file, cloud, true)) {
    throw StageError(stage, file.string() + ": cannot read the point cloud (not a PLY?)");
  }
  return cloud;
}

o3d::TriangleMesh readMesh(const fs::path& file, const std::string& stage) {
  Survey::requireExists(file, stage, "mesh");
  if (const std::string problem = readProblem(file, true); !problem.empty()) {
    throw StageError(stage, file.string() + ": cannot read the mesh: " + problem);
  }
  o3d::TriangleMesh mesh;
  if (!openTriangleMesh(file, mesh)) {
    throw StageError(stage, file.string() + ": cannot read the mesh");
  }
  if (mesh.triangles_.empty()) {
    throw StageError(stage, file.string() + ": the mesh has no triangles");
  }
  return mesh;
}

void writeMeshPly(const fs::path& file, const o3d::TriangleMesh& mesh) {
  PlyData ply;
  ply.positions = mesh.vertices_;
  if (mesh.HasVertexNormals()) ply.normals = mesh.vertex_normals_;
  if (mesh.HasVertexColors()) {
    ply.colors.reserve(mesh.vertex_colors_.size());
    for (const auto& c : mesh.vertex_colors_) {
      ply.colors.push_back(
          (c.cwiseMax(0.0).cwiseMin(1.0) * 255.0).array().round().cast<uint8_t>().matrix());
    }
  }
  ply.triangles.reserve(mesh.triangles_.size());
  for (const auto& t : mesh.triangles_) {
    ply.triangles.push_back(
        {static_cast<uint32_t>(t(0)), static_cast<uint32_t>(t(1)), static_cast<uint32_t>(t(2))});
  }
  writePly(file, ply);
}

}  // namespace auv::recon::scene
