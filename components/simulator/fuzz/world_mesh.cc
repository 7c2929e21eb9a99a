// Fuzz harness: the world meshes a user brings to the simulator (scenario `world.mesh`,
// `auv sim check`): PLY (ascii and binary) and OBJ (+ MTL + texture image), read by loadMesh
// (Open3D's readers, then the simulator's conversion) and checked by validateMesh, as
// loadWorldMeshBeforeChanges does. A clear error is a ConfigError naming the file; anything
// else (a crash, a sanitizer report, another exception) is a bug.
//
// Input: the mesh file's bytes, read once as `mesh.ply` and once as `mesh.obj` in a folder of
// this process. If the input holds the line kMaterialMarker ("\n#auv-fuzz-mtl\n"), the bytes
// before it are the mesh file and the bytes after it its material library `mesh.mtl` (absent
// otherwise). The folder also holds the texture images the seeds' material library names
// (written once by saveMesh), so that textured OBJ files reach the texture conversion.
#include <unistd.h>

#include <open3d/geometry/TriangleMesh.h>
#include <open3d/io/TriangleMeshIO.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "auv/sim/common/yaml_section.h"
#include "auv/sim/world/mesh.h"

namespace fs = std::filesystem;
using auv::sim::ConfigError;
using auv::sim::Mesh;

namespace {

const std::string kMaterialMarker = "\n#auv-fuzz-mtl\n";

/// A coloured tetrahedron-like wedge: 5 vertices, 4 triangles (one degenerate, dropped).
Mesh colouredMesh() {
  Mesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.5f, 0, 0}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {0, 4, 1}};
  m.vertex_colors = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.5f, 0.5f, 0.5f}, {1, 1, 1}};
  return m;
}

/// A square of two triangles with a 4x4 texture.
Mesh texturedMesh() {
  Mesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  m.triangle_uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 0}, {1, 1}, {0, 1}};
  m.texture = cv::Mat(4, 4, CV_8UC3, cv::Scalar(10, 20, 30));
  m.texture.at<cv::Vec3b>(0, 0) = cv::Vec3b(0, 0, 255);
  return m;
}

std::string readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void writeFile(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

/// This process's folder, made once with the texture images of texturedMesh() saved as
/// `mesh.obj` (so a `mesh.mtl` naming them finds them).
const fs::path& workFolder() {
  static const fs::path folder = [] {
    const fs::path dir =
        fs::temp_directory_path() / ("auv_fuzz_sim_mesh_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    auv::sim::saveMesh(texturedMesh(), (dir / "mesh.obj").string());
    return dir;
  }();
  return folder;
}

struct RemoveWorkFolder {
  ~RemoveWorkFolder() {
    std::error_code ignored;
    fs::remove_all(fs::temp_directory_path() / ("auv_fuzz_sim_mesh_" + std::to_string(::getpid())),
                   ignored);
  }
} remove_work_folder;

void loadAndValidate(const fs::path& file) {
  try {
    Mesh mesh = auv::sim::loadMesh(file.string());
    // As a scenario with world.default_color does for a mesh without colours or texture.
    if (!mesh.hasTexture() && !mesh.hasVertexColors()) {
      mesh.vertex_colors.assign(mesh.vertices.size(), Eigen::Vector3f(0.5f, 0.5f, 0.5f));
    }
    auv::sim::validateMesh(mesh);
  } catch (const ConfigError&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  const fs::path& dir = workFolder();
  const size_t marker = input.find(kMaterialMarker);
  const std::string mesh = input.substr(0, marker);
  if (marker == std::string::npos) {
    std::error_code ignored;
    fs::remove(dir / "mesh.mtl", ignored);
  } else {
    writeFile(dir / "mesh.mtl", input.substr(marker + kMaterialMarker.size()));
  }
  for (const char* name : {"mesh.ply", "mesh.obj"}) {
    writeFile(dir / name, mesh);
    loadAndValidate(dir / name);
  }
  return 0;
}

/// A coloured mesh as binary PLY and as OBJ, a textured one as OBJ + MTL, written by
/// saveMesh; and the coloured one as ascii PLY (Open3D's writer: saveMesh writes binary only).
std::vector<std::string> auvFuzzSeeds() {
  const fs::path dir =
      fs::temp_directory_path() / ("auv_fuzz_sim_mesh_seeds_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::vector<std::string> seeds;
  auv::sim::saveMesh(colouredMesh(), (dir / "coloured.ply").string());
  seeds.push_back(readFile(dir / "coloured.ply"));
  auv::sim::saveMesh(colouredMesh(), (dir / "coloured.obj").string());
  seeds.push_back(readFile(dir / "coloured.obj"));
  // Saved as mesh.obj: its mesh.mtl names the images workFolder() holds.
  auv::sim::saveMesh(texturedMesh(), (dir / "mesh.obj").string());
  seeds.push_back(readFile(dir / "mesh.obj") + kMaterialMarker + readFile(dir / "mesh.mtl"));
  open3d::geometry::TriangleMesh ascii;
  for (const auto& v : colouredMesh().vertices) ascii.vertices_.push_back(v.cast<double>());
  for (const auto& c : colouredMesh().vertex_colors)
    ascii.vertex_colors_.push_back(c.cast<double>());
  ascii.triangles_ = colouredMesh().triangles;
  open3d::io::WriteTriangleMesh((dir / "ascii.ply").string(), ascii, /*write_ascii=*/true);
  seeds.push_back(readFile(dir / "ascii.ply"));
  fs::remove_all(dir);
  return seeds;
}
