#pragma once
// Z-buffer rasterisation of a triangle mesh into a pinhole view: per pixel the nearest face and
// its depth. The texturing uses it for visibility (the mesh occluding itself) and the renderer
// for images of the textured model. Pixel centres at integer coordinates (OpenCV).

#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "auv/recon/scene/camera.h"

namespace auv::recon::texture {

/// A posed pinhole view. The lens distortion of `camera` is ignored: the texturing works on the
/// undistorted (corrected) images.
struct ViewGeometry {
  scene::Camera camera;
  Eigen::Isometry3d world_to_camera = Eigen::Isometry3d::Identity();

  Eigen::Vector3d toCamera(const Eigen::Vector3d& world) const { return world_to_camera * world; }
  Eigen::Vector3d center() const { return world_to_camera.inverse().translation(); }
  /// Pixel of a point in the camera frame (z > 0).
  Eigen::Vector2d project(const Eigen::Vector3d& camera_point) const {
    return {camera.fx * camera_point.x() / camera_point.z() + camera.cx,
            camera.fy * camera_point.y() / camera_point.z() + camera.cy};
  }
  int width() const { return camera.width; }
  int height() const { return camera.height; }
};

struct RasterBuffers {
  cv::Mat1f depth;  ///< camera z of the nearest surface, +inf where none
  cv::Mat1i face;   ///< index of the nearest face, -1 where none
};

/// Rasterises every face with all three vertices in front of `near` (m); faces crossing the
/// near plane are skipped. Both sides of a face are drawn.
RasterBuffers rasterize(const std::vector<Eigen::Vector3d>& vertices,
                        const std::vector<Eigen::Vector3i>& faces, const ViewGeometry& view,
                        double near = 1e-3);

/// Perspective-correct barycentric coordinates, in `face`'s vertex order, of the surface point
/// seen at `pixel` (the coordinates may leave [0, 1] outside the face's projection).
Eigen::Vector3d barycentricAt(const std::vector<Eigen::Vector3d>& vertices,
                              const Eigen::Vector3i& face, const ViewGeometry& view,
                              const Eigen::Vector2d& pixel);

/// Screen-space barycentric coordinates of `p` in the 2D triangle (a, b, c); false when the
/// triangle is degenerate.
bool barycentric2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                   const Eigen::Vector2d& p, Eigen::Vector3d& weights);

/// Bilinear colour (BGR, 0..255) at a pixel, clamped to the image.
Eigen::Vector3f sampleBilinear(const cv::Mat3b& image, double x, double y);

}  // namespace auv::recon::texture
