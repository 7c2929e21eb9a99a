#include "auv/recon/dense/view.h"

#include <cmath>
#include <filesystem>
#include <stdexcept>

#include "auv/recon/common/stage_error.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace auv::recon::dense {

View View::fromImage(const scene::Reconstruction& model, const scene::Image& image) {
  const scene::Camera& camera = model.cameraOf(image);
  if (camera.hasDistortion()) {
    throw StageError("dense", "image " + image.name + " has camera " + std::to_string(camera.id) +
                                  " with lens distortion (model " +
                                  scene::cameraModelName(camera.model) +
                                  "); dense matching needs undistorted (PINHOLE) images");
  }
  View view;
  view.image_id = image.id;
  view.camera_id = image.camera_id;
  view.name = image.name;
  view.width = camera.width;
  view.height = camera.height;
  view.source_width = camera.width;
  view.source_height = camera.height;
  view.K = camera.K();
  view.R = image.rotation();
  view.t = image.t_cw;
  return view;
}

View View::scaled(int width, int height) const {
  View out = *this;
  const double sx = static_cast<double>(width) / this->width;
  const double sy = static_cast<double>(height) / this->height;
  out.width = width;
  out.height = height;
  out.K(0, 0) = K(0, 0) * sx;
  out.K(1, 1) = K(1, 1) * sy;
  out.K(0, 1) = K(0, 1) * sx;
  out.K(0, 2) = (K(0, 2) + 0.5) * sx - 0.5;
  out.K(1, 2) = (K(1, 2) + 0.5) * sy - 0.5;
  if (width != this->width || height != this->height) {
    if (!grey.empty()) cv::resize(grey, out.grey, {width, height}, 0, 0, cv::INTER_AREA);
    if (!color.empty()) cv::resize(color, out.color, {width, height}, 0, 0, cv::INTER_AREA);
  }
  return out;
}

Eigen::Vector3d View::backProject(double x, double y, double depth) const {
  const Eigen::Vector3d camera((x - K(0, 2)) / K(0, 0) * depth, (y - K(1, 2)) / K(1, 1) * depth,
                               depth);
  return R.transpose() * (camera - t);
}

void loadImages(View& view, const std::string& folder) {
  const std::filesystem::path file = std::filesystem::path(folder) / view.name;
  cv::Mat image = cv::imread(file.string(), cv::IMREAD_COLOR);
  if (image.empty()) {
    throw std::runtime_error(
        "dense: cannot read image " + file.string() +
        (std::filesystem::exists(file) ? " (not a readable image)" : " (missing)"));
  }
  if (image.cols != view.source_width || image.rows != view.source_height) {
    throw std::runtime_error(
        "dense: image " + file.string() + " is " + std::to_string(image.cols) + "x" +
        std::to_string(image.rows) + " px but its camera in the model is " +
        std::to_string(view.source_width) + "x" + std::to_string(view.source_height));
  }
  if (image.cols != view.width || image.rows != view.height) {
    cv::resize(image, image, {view.width, view.height}, 0, 0, cv::INTER_AREA);
  }
  view.color = image;
  cv::Mat grey;
  cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  grey.convertTo(view.grey, CV_32F);
}

cv::Size limitedSize(int width, int height, int max_size) {
  const int longer = std::max(width, height);
  if (max_size <= 0 || longer <= max_size) return {width, height};
  const double s = static_cast<double>(max_size) / longer;
  return {std::max(1, static_cast<int>(std::lround(width * s))),
          std::max(1, static_cast<int>(std::lround(height * s)))};
}

}  // namespace auv::recon::dense
