#include "auv/recon/sfm/undistorted_model.h"

#include <map>
#include <memory>
#include <string>
#include <system_error>

#include <opencv2/imgcodecs.hpp>

#include "auv/recon/calibration/undistort.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/scene/colmap_text.h"

namespace fs = std::filesystem;

namespace auv::recon::sfm {

namespace {

/// One undistorter per distorted camera (its maps are computed once).
std::map<uint32_t, std::unique_ptr<calibration::Undistorter>> undistorters(
    const scene::Reconstruction& model) {
  std::map<uint32_t, std::unique_ptr<calibration::Undistorter>> out;
  for (const auto& [id, camera] : model.cameras) {
    if (!camera.hasDistortion()) continue;
    if (camera.distortion.size() > 5) {
      throw StageError("sfm", "camera " + std::to_string(id) + " is " +
                                  scene::cameraModelName(camera.model) +
                                  ": only the OPENCV lens (k1 k2 p1 p2) can be undistorted here");
    }
    out[id] = std::make_unique<calibration::Undistorter>(calibration::calibrationOf(camera),
                                                         calibration::UndistortOptions());
  }
  return out;
}

scene::Reconstruction undistortWith(
    const scene::Reconstruction& model,
    const std::map<uint32_t, std::unique_ptr<calibration::Undistorter>>& lenses) {
  scene::Reconstruction out = model;
  for (const auto& [id, lens] : lenses) {
    const cv::Mat& K = lens->undistorted().camera_matrix;
    scene::Camera& camera = out.cameras.at(id);
    camera = scene::Camera::pinhole(id, camera.width, camera.height, K.at<double>(0, 0),
                                    K.at<double>(1, 1), K.at<double>(0, 2), K.at<double>(1, 2));
  }
  for (auto& [id, image] : out.images) {
    const scene::Camera& distorted = model.cameraOf(model.images.at(id));
    if (!lenses.count(distorted.id)) continue;
    const scene::Camera& pinhole = out.cameraOf(image);
    for (Eigen::Vector2d& pixel : image.points2d) {
      const Eigen::Vector2d n = distorted.pixelToNormalized(pixel);
      pixel = {pinhole.fx * n.x() + pinhole.cx, pinhole.fy * n.y() + pinhole.cy};
    }
  }
  return out;
}

}  // namespace

scene::Reconstruction undistortedModel(const scene::Reconstruction& model) {
  return undistortWith(model, undistorters(model));
}

void writeUndistortedWorkspace(const scene::Reconstruction& model, const fs::path& images,
                               const fs::path& folder) {
  const auto lenses = undistorters(model);
  for (const auto& [id, image] : model.images) {
    const fs::path source = images / image.name;
    const fs::path target = folder / image.name;
    fs::create_directories(target.parent_path());
    const auto lens = lenses.find(image.camera_id);
    if (lens == lenses.end()) {
      // A pinhole camera's image as it is: a hard link when the file system allows one.
      std::error_code error;
      fs::create_hard_link(source, target, error);
      if (error) fs::copy_file(source, target, fs::copy_options::overwrite_existing);
      continue;
    }
    const cv::Mat distorted = cv::imread(source.string(), cv::IMREAD_UNCHANGED);
    if (distorted.empty()) {
      throw StageError("sfm", source.string() + ": cannot read the image to undistort it");
    }
    cv::Mat undistorted;
    try {
      undistorted = lens->second->apply(distorted);
    } catch (const std::invalid_argument& e) {
      throw StageError("sfm", source.string() + ": " + e.what());
    }
    if (!cv::imwrite(target.string(), undistorted)) {
      throw StageError("sfm", target.string() + ": cannot write the undistorted image");
    }
  }
  const fs::path sparse = folder / "sparse";
  fs::create_directories(sparse);
  scene::writeColmapText(undistortWith(model, lenses), sparse);
}

}  // namespace auv::recon::sfm
