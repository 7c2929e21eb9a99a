#pragma once
// A posed pinhole view at the resolution dense matching works at: intrinsics scaled from the
// sparse model's camera, world -> camera pose, and (when loaded) its grey and colour images.

#include <cstdint>
#include <string>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "auv/recon/scene/reconstruction.h"

namespace auv::recon::dense {

struct View {
  uint32_t image_id = 0;
  uint32_t camera_id = 0;
  std::string name;                         ///< relative to the image folder (corrected/)
  int width = 0, height = 0;                ///< px at this view's scale
  int source_width = 0, source_height = 0;  ///< px of the image file (the model's camera)
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  ///< world -> camera
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  cv::Mat grey;   ///< CV_32F, 0..255; empty until loaded
  cv::Mat color;  ///< CV_8UC3 (BGR); empty until loaded

  /// The view of a registered image with its camera's intrinsics (a PINHOLE model is
  /// required: dense matching works on undistorted images). Throws StageError naming the
  /// image when its camera has lens distortion.
  static View fromImage(const scene::Reconstruction& model, const scene::Image& image);

  /// This view resampled to `width` x `height` (OpenCV pixel centres: x' = (x + 0.5) s - 0.5);
  /// loaded images are resized with area averaging.
  View scaled(int width, int height) const;

  Eigen::Vector3d center() const { return -R.transpose() * t; }
  Eigen::Vector3d toCamera(const Eigen::Vector3d& world) const { return R * world + t; }
  /// World point of pixel (x, y) at `depth` (camera z).
  Eigen::Vector3d backProject(double x, double y, double depth) const;
  /// Pixel of a camera-frame point (z > 0 expected).
  Eigen::Vector2d project(const Eigen::Vector3d& camera_point) const {
    return {K(0, 0) * camera_point.x() / camera_point.z() + K(0, 2),
            K(1, 1) * camera_point.y() / camera_point.z() + K(1, 2)};
  }
};

/// Reads `folder / view.name`, scales it to the view's size and fills `grey` and `color`.
/// Throws std::runtime_error naming the file when it is missing or unreadable.
void loadImages(View& view, const std::string& folder);

/// The width and height of an image scaled so that its longer side is at most `max_size`
/// (0: unchanged).
cv::Size limitedSize(int width, int height, int max_size);

}  // namespace auv::recon::dense
