// Fuzz harness: COLMAP text models as the reconstruction reads them from outside (a model made
// by COLMAP for `auv recon` to use or compare with, the simulator's ground truth): each file
// alone (readColmapCameras, readColmapImages, readColmapPoints, as evaluate reads the ground
// truth) and the three together (readColmapText, with its consistency check). A clear error is
// a std::runtime_error naming the file (and line); anything else (a crash, a sanitizer report,
// another exception) is a bug.
//
// Input: cameras.txt, images.txt and points3D.txt one after the other, separated by the line
// kFileMarker ("\n#auv-fuzz-file\n": a comment to the reader); with two parts there is no
// points3D.txt (optional to readColmapText), after a third marker the rest is ignored.
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include "auv/recon/scene/colmap_text.h"

namespace fs = std::filesystem;
namespace scene = auv::recon::scene;

namespace {

const std::string kFileMarker = "\n#auv-fuzz-file\n";
const char* const kFiles[] = {"cameras.txt", "images.txt", "points3D.txt"};

fs::path folderOf(const std::string& what) {
  return fs::temp_directory_path() / ("auv_fuzz_recon_" + what + "_" + std::to_string(::getpid()));
}

std::string readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

const fs::path& workFolder() {
  static const fs::path folder = [] {
    fs::create_directories(folderOf("colmap"));
    return folderOf("colmap");
  }();
  return folder;
}

struct RemoveWorkFolder {
  ~RemoveWorkFolder() {
    std::error_code ignored;
    fs::remove_all(folderOf("colmap"), ignored);
  }
} remove_work_folder;

/// Two cameras (one distorted), two images observing three points; one keypoint without a point.
scene::Reconstruction smallModel() {
  scene::Reconstruction r;
  r.cameras[1] = scene::Camera::pinhole(1, 64, 48, 50, 51, 31.5, 23.5);
  scene::Camera distorted = scene::Camera::pinhole(2, 80, 60, 60, 60, 40, 30);
  distorted.model = scene::CameraModel::OPENCV;
  distorted.distortion = {0.08, 0.02, 0.001, -0.002};
  r.cameras[2] = distorted;
  for (uint64_t id = 1; id <= 3; ++id) {
    scene::Point3D p;
    p.id = id;
    p.xyz = Eigen::Vector3d(0.1 * id, -0.2, 5);
    p.rgb << 10, static_cast<uint8_t>(id), 200;
    r.points[id] = p;
  }
  for (uint32_t id = 1; id <= 2; ++id) {
    scene::Image image;
    image.id = id;
    image.camera_id = id;
    image.name = "cam" + std::to_string(id) + "/frame_" + std::to_string(id) + ".png";
    image.q_cw = Eigen::AngleAxisd(0.05 * id, Eigen::Vector3d(0.2, 1, 0.1).normalized());
    image.t_cw = Eigen::Vector3d(0.3 * id, -0.1, 0.05);
    image.points2d.emplace_back(1, 2);
    image.point3d_ids.push_back(scene::kNoPoint3D);
    for (auto& [pid, p] : r.points) {
      image.points2d.push_back(r.cameras[image.camera_id].project(image.toCamera(p.xyz)));
      image.point3d_ids.push_back(static_cast<int64_t>(pid));
      p.track.push_back({id, static_cast<uint32_t>(image.points2d.size() - 1)});
    }
    r.images[id] = image;
  }
  r.updatePointErrors();
  return r;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  const fs::path& dir = workFolder();
  size_t begin = 0;
  for (const char* name : kFiles) {
    const fs::path file = dir / name;
    if (begin == std::string::npos) {  // fewer parts: no such file
      std::error_code ignored;
      fs::remove(file, ignored);
      continue;
    }
    const size_t end = input.find(kFileMarker, begin);
    std::ofstream(file, std::ios::binary | std::ios::trunc)
        << input.substr(begin, end == std::string::npos ? std::string::npos : end - begin);
    begin = end == std::string::npos ? end : end + kFileMarker.size();
  }
  try {
    scene::readColmapCameras(dir / kFiles[0]);
  } catch (const std::runtime_error&) {
  }
  try {
    scene::readColmapImages(dir / kFiles[1]);
  } catch (const std::runtime_error&) {
  }
  if (fs::exists(dir / kFiles[2])) {
    try {
      scene::readColmapPoints(dir / kFiles[2]);
    } catch (const std::runtime_error&) {
    }
  }
  try {
    scene::readColmapText(dir);
  } catch (const std::runtime_error&) {
  }
  return 0;
}

/// A small model written by writeColmapText: all three files, and without points3D.txt.
std::vector<std::string> auvFuzzSeeds() {
  const fs::path dir = folderOf("colmap_seeds");
  scene::writeColmapText(smallModel(), dir);
  const std::string cameras = readFile(dir / kFiles[0]), images = readFile(dir / kFiles[1]),
                    points = readFile(dir / kFiles[2]);
  fs::remove_all(dir);
  return {cameras + kFileMarker + images + kFileMarker + points, cameras + kFileMarker + images};
}
