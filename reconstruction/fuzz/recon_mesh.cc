// Fuzz harness: the meshes and clouds the stages read: PLY (ascii and binary) and OBJ through
// Open3D's readers (scene::readMesh: the mesh of this or another survey, the simulator's world
// mesh as ground truth; scene::readCloud: the dense stage's fused.ply), and the textured model
// as OBJ + MTL + PNG (texture::readObj, the project's own OBJ reader, read by `evaluate`). A
// clear error is a StageError naming the file (readMesh, readCloud) or a std::runtime_error
// naming the file and line (readObj); anything else (a crash, a sanitizer report, another
// exception) is a bug.
//
// Input: the file's bytes, read as `mesh.ply` (readMesh, readCloud) and as `mesh.obj` (readMesh,
// readObj) in a folder of this process. If the input holds the line kMaterialMarker
// ("\n#auv-fuzz-mtl\n"), the bytes before it are the file and the bytes after it its material
// library `mesh.mtl` (absent otherwise). The folder also holds the atlas page the seeds'
// material library names (written once by writeObj), so that an OBJ reaches its texture.
#include <unistd.h>

#include <open3d/geometry/PointCloud.h>
#include <open3d/geometry/TriangleMesh.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "auv/recon/common/stage_error.h"
#include "auv/recon/scene/mesh_io.h"
#include "auv/recon/scene/ply.h"
#include "auv/recon/texture/textured_model.h"

namespace fs = std::filesystem;
using auv::recon::StageError;

namespace {

const std::string kMaterialMarker = "\n#auv-fuzz-mtl\n";
const char* const kStage = "fuzz";

fs::path folderOf(const std::string& what) {
  return fs::temp_directory_path() / ("auv_fuzz_recon_" + what + "_" + std::to_string(::getpid()));
}

/// A square of two triangles on a 4x4 atlas page.
auv::recon::texture::TexturedModel texturedModel() {
  auv::recon::texture::TexturedModel model;
  model.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  model.faces = {{0, 1, 2}, {0, 2, 3}};
  model.face_uvs = {{{{0, 0}, {1, 0}, {1, 1}}}, {{{0, 0}, {1, 1}, {0, 1}}}};
  model.face_page = {0, 0};
  model.pages = {cv::Mat3b(4, 4, cv::Vec3b(10, 20, 30))};
  return model;
}

/// A wedge with normals and colours, the way the mesh stage leaves it.
open3d::geometry::TriangleMesh wedge() {
  open3d::geometry::TriangleMesh mesh;
  mesh.vertices_ = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  mesh.triangles_ = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  mesh.vertex_normals_.assign(4, Eigen::Vector3d(0, 0, 1));
  mesh.vertex_colors_ = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.5, 0.5, 0.5}};
  return mesh;
}

std::string readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void writeFile(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

/// This process's folder, made once with the atlas page of texturedModel() written as `mesh`.
const fs::path& workFolder() {
  static const fs::path folder = [] {
    const fs::path dir = folderOf("mesh");
    fs::create_directories(dir);
    auv::recon::texture::writeObj(texturedModel(), dir, "mesh");
    return dir;
  }();
  return folder;
}

struct RemoveWorkFolder {
  ~RemoveWorkFolder() {
    std::error_code ignored;
    fs::remove_all(folderOf("mesh"), ignored);
  }
} remove_work_folder;

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  const fs::path& dir = workFolder();
  const size_t marker = input.find(kMaterialMarker);
  const std::string file = input.substr(0, marker);
  if (marker == std::string::npos) {
    std::error_code ignored;
    fs::remove(dir / "mesh.mtl", ignored);
  } else {
    writeFile(dir / "mesh.mtl", input.substr(marker + kMaterialMarker.size()));
  }
  writeFile(dir / "mesh.ply", file);
  writeFile(dir / "mesh.obj", file);
  for (const char* name : {"mesh.ply", "mesh.obj"}) {
    try {
      auv::recon::scene::readMesh(dir / name, kStage);
    } catch (const StageError&) {
    }
  }
  try {
    auv::recon::scene::readCloud(dir / "mesh.ply", kStage, "dense");
  } catch (const StageError&) {
  }
  try {
    auv::recon::texture::readObj(dir / "mesh.obj");
  } catch (const std::runtime_error&) {
  }
  return 0;
}

/// A mesh with normals and colours (writeMeshPly), a cloud with normals, colours, a scalar field
/// and camera glyphs as edges (writePly), both binary PLY, the project's only PLY; the textured
/// model as OBJ + MTL (writeObj). The project writes no ascii PLY and no untextured OBJ.
std::vector<std::string> auvFuzzSeeds() {
  const fs::path dir = folderOf("mesh_seeds");
  fs::create_directories(dir);
  std::vector<std::string> seeds;
  auv::recon::scene::writeMeshPly(dir / "mesh.ply", wedge());
  seeds.push_back(readFile(dir / "mesh.ply"));
  auv::recon::scene::PlyData cloud;
  cloud.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  cloud.normals.assign(3, Eigen::Vector3d(0, 0, 1));
  cloud.colors.assign(3, Eigen::Matrix<uint8_t, 3, 1>(10, 20, 30));
  cloud.scalars = {{"distance", {0.5f, -0.25f, 1.0f}}};
  auv::recon::scene::CameraGlyph glyph{Eigen::Vector3d(0, 0, -2),
                                       Eigen::Matrix3d::Identity(),
                                       0.2,
                                       0.1,
                                       0.3,
                                       Eigen::Matrix<uint8_t, 3, 1>(255, 0, 0)};
  auv::recon::scene::appendCameraGlyph(glyph, cloud);
  cloud.scalars[0].second.resize(cloud.positions.size(), 0.0f);
  auv::recon::scene::writePly(dir / "cloud.ply", cloud);
  seeds.push_back(readFile(dir / "cloud.ply"));
  auv::recon::texture::writeObj(texturedModel(), dir, "mesh");
  seeds.push_back(readFile(dir / "mesh.obj") + kMaterialMarker + readFile(dir / "mesh.mtl"));
  fs::remove_all(dir);
  return seeds;
}
