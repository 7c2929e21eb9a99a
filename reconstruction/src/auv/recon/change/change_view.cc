#include "auv/recon/change/change_view.h"

#include <algorithm>
#include <cmath>

#include <open3d/geometry/BoundingVolume.h>
#include <opencv2/imgcodecs.hpp>

#include "auv/recon/texture/rasterizer.h"

namespace auv::recon::change {

void writeChangeView(const std::filesystem::path& file, const open3d::geometry::TriangleMesh& mesh,
                     const ChangeViewOptions& options) {
  cv::Mat3b image(options.height, options.width, cv::Vec3b(255, 255, 255));
  if (!mesh.vertices_.empty() && !mesh.triangles_.empty()) {
    const Eigen::Vector3d centre = mesh.GetAxisAlignedBoundingBox().GetCenter();
    double radius = 0.0;
    for (const Eigen::Vector3d& v : mesh.vertices_) radius = std::max(radius, (v - centre).norm());
    const double deg = M_PI / 180.0;
    const double fov = options.fov_deg * deg;
    const double distance = 1.05 * radius / std::sin(0.5 * fov * options.height / options.width);
    // From the centre towards the camera (NED: north, east, down; up is -z).
    const Eigen::Vector3d back(
        std::cos(options.elevation_deg * deg) * std::cos(options.azimuth_deg * deg),
        std::cos(options.elevation_deg * deg) * std::sin(options.azimuth_deg * deg),
        -std::sin(options.elevation_deg * deg));
    const Eigen::Vector3d eye = centre + distance * back;
    // Camera axes (OpenCV: x right, y down, z forward).
    const Eigen::Vector3d forward = -back;
    const Eigen::Vector3d right = forward.cross(Eigen::Vector3d(0, 0, -1)).normalized();
    const Eigen::Vector3d down = forward.cross(right);
    Eigen::Matrix3d rotation;
    rotation.row(0) = right;
    rotation.row(1) = down;
    rotation.row(2) = forward;
    texture::ViewGeometry view;
    const double f = 0.5 * options.width / std::tan(0.5 * fov);
    view.camera = scene::Camera::pinhole(1, options.width, options.height, f, f,
                                         0.5 * (options.width - 1), 0.5 * (options.height - 1));
    view.world_to_camera.linear() = rotation;
    view.world_to_camera.translation() = -rotation * eye;
    std::vector<Eigen::Vector3i> faces(mesh.triangles_.begin(), mesh.triangles_.end());
    const texture::RasterBuffers raster = texture::rasterize(mesh.vertices_, faces, view);
    const bool coloured = mesh.vertex_colors_.size() == mesh.vertices_.size();
    for (int y = 0; y < options.height; ++y) {
      for (int x = 0; x < options.width; ++x) {
        const int face = raster.face(y, x);
        if (face < 0) continue;
        const Eigen::Vector3i& t = faces[static_cast<size_t>(face)];
        const Eigen::Vector3d w =
            texture::barycentricAt(mesh.vertices_, t, view, Eigen::Vector2d(x, y));
        Eigen::Vector3d colour(0.7, 0.7, 0.7);
        if (coloured)
          colour = w.x() * mesh.vertex_colors_[t.x()] + w.y() * mesh.vertex_colors_[t.y()] +
                   w.z() * mesh.vertex_colors_[t.z()];
        // Lambert with the light at the camera (both sides lit), a third ambient.
        const Eigen::Vector3d normal = (mesh.vertices_[t.y()] - mesh.vertices_[t.x()])
                                           .cross(mesh.vertices_[t.z()] - mesh.vertices_[t.x()])
                                           .normalized();
        const double shade = 0.35 + 0.65 * std::abs(normal.dot(forward));
        const Eigen::Vector3d rgb = (255.0 * shade * colour).cwiseMax(0.0).cwiseMin(255.0);
        image(y, x) = cv::Vec3b(static_cast<uchar>(rgb.z()), static_cast<uchar>(rgb.y()),
                                static_cast<uchar>(rgb.x()));
      }
    }
  }
  const std::filesystem::path temporary = file.string() + ".part.png";
  if (!cv::imwrite(temporary.string(), image))
    throw std::runtime_error(file.string() + ": cannot be written");
  std::filesystem::rename(temporary, file);
}

}  // namespace auv::recon::change
