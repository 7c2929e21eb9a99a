#pragma once
// A camera's intrinsics (one per physical camera; several images share it).
//
// Pixel convention: OpenCV's (pixel centres at integer coordinates) everywhere in memory; the
// COLMAP text files add 0.5 to principal points and keypoints (colmap_text.h), as COLMAP does.

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace auv::recon::scene {

/// COLMAP's model names; the reconstruction works on undistorted images (PINHOLE), the others
/// are read so that ground truth with lens distortion can be compared.
enum class CameraModel { SIMPLE_PINHOLE, PINHOLE, OPENCV, FULL_OPENCV };

std::string cameraModelName(CameraModel model);
/// Throws std::invalid_argument for a name it does not know.
CameraModel cameraModelFromName(const std::string& name);

struct Camera {
  uint32_t id = 0;
  CameraModel model = CameraModel::PINHOLE;
  int width = 0, height = 0;              ///< px
  double fx = 0, fy = 0, cx = 0, cy = 0;  ///< px, OpenCV convention
  /// OpenCV order: k1 k2 p1 p2 (OPENCV) or k1 k2 p1 p2 k3 k4 k5 k6 (FULL_OPENCV); empty for
  /// the pinhole models.
  std::vector<double> distortion;

  /// A pinhole camera from a calibration matrix.
  static Camera pinhole(uint32_t id, int width, int height, double fx, double fy, double cx,
                        double cy);

  Eigen::Matrix3d K() const;
  bool hasDistortion() const;
  /// Pixel of a point in the camera frame (z > 0 in front), with the lens distortion.
  Eigen::Vector2d project(const Eigen::Vector3d& point_camera) const;
  /// Normalised image coordinates (x/z, y/z) of a pixel, distortion removed iteratively.
  Eigen::Vector2d pixelToNormalized(const Eigen::Vector2d& pixel) const;
  bool inImage(const Eigen::Vector2d& pixel) const;
};

}  // namespace auv::recon::scene
