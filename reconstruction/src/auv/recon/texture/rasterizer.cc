#include "auv/recon/texture/rasterizer.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace auv::recon::texture {

bool barycentric2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                   const Eigen::Vector2d& p, Eigen::Vector3d& weights) {
  const double area = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
  if (std::abs(area) < 1e-12) return false;
  const double w0 = ((b.x() - p.x()) * (c.y() - p.y()) - (b.y() - p.y()) * (c.x() - p.x())) / area;
  const double w1 = ((c.x() - p.x()) * (a.y() - p.y()) - (c.y() - p.y()) * (a.x() - p.x())) / area;
  weights = Eigen::Vector3d(w0, w1, 1.0 - w0 - w1);
  return true;
}

RasterBuffers rasterize(const std::vector<Eigen::Vector3d>& vertices,
                        const std::vector<Eigen::Vector3i>& faces, const ViewGeometry& view,
                        double near) {
  const int width = view.width(), height = view.height();
  RasterBuffers buffers;
  buffers.depth = cv::Mat1f(height, width, std::numeric_limits<float>::infinity());
  buffers.face = cv::Mat1i(height, width, -1);
  std::vector<Eigen::Vector3d> camera_points(vertices.size());
  for (size_t v = 0; v < vertices.size(); ++v) camera_points[v] = view.toCamera(vertices[v]);

  for (size_t f = 0; f < faces.size(); ++f) {
    const Eigen::Vector3i& face = faces[f];
    const Eigen::Vector3d& p0 = camera_points[face(0)];
    const Eigen::Vector3d& p1 = camera_points[face(1)];
    const Eigen::Vector3d& p2 = camera_points[face(2)];
    if (p0.z() <= near || p1.z() <= near || p2.z() <= near) continue;
    const Eigen::Vector2d a = view.project(p0), b = view.project(p1), c = view.project(p2);
    const int x_min = std::max(0, static_cast<int>(std::ceil(std::min({a.x(), b.x(), c.x()}))));
    const int x_max =
        std::min(width - 1, static_cast<int>(std::floor(std::max({a.x(), b.x(), c.x()}))));
    const int y_min = std::max(0, static_cast<int>(std::ceil(std::min({a.y(), b.y(), c.y()}))));
    const int y_max =
        std::min(height - 1, static_cast<int>(std::floor(std::max({a.y(), b.y(), c.y()}))));
    if (x_min > x_max || y_min > y_max) continue;
    const double area = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
    if (std::abs(area) < 1e-12) continue;
    // Screen-space barycentrics are affine in x and y: step them incrementally.
    const double inv_z0 = 1.0 / p0.z(), inv_z1 = 1.0 / p1.z(), inv_z2 = 1.0 / p2.z();
    for (int y = y_min; y <= y_max; ++y) {
      for (int x = x_min; x <= x_max; ++x) {
        const double w0 = ((b.x() - x) * (c.y() - y) - (b.y() - y) * (c.x() - x)) / area;
        const double w1 = ((c.x() - x) * (a.y() - y) - (c.y() - y) * (a.x() - x)) / area;
        const double w2 = 1.0 - w0 - w1;
        constexpr double kEdge = -1e-9;  // pixels exactly on a shared edge go to either face
        if (w0 < kEdge || w1 < kEdge || w2 < kEdge) continue;
        // 1/z is affine in screen space.
        const float z = static_cast<float>(1.0 / (w0 * inv_z0 + w1 * inv_z1 + w2 * inv_z2));
        float& depth = buffers.depth(y, x);
        if (z < depth) {
          depth = z;
          buffers.face(y, x) = static_cast<int>(f);
        }
      }
    }
  }
  return buffers;
}

Eigen::Vector3d barycentricAt(const std::vector<Eigen::Vector3d>& vertices,
                              const Eigen::Vector3i& face, const ViewGeometry& view,
                              const Eigen::Vector2d& pixel) {
  const Eigen::Vector3d p0 = view.toCamera(vertices[face(0)]);
  const Eigen::Vector3d p1 = view.toCamera(vertices[face(1)]);
  const Eigen::Vector3d p2 = view.toCamera(vertices[face(2)]);
  Eigen::Vector3d w;
  if (!barycentric2d(view.project(p0), view.project(p1), view.project(p2), pixel, w)) {
    return Eigen::Vector3d::Constant(1.0 / 3.0);
  }
  // Screen-space weights divided by depth, renormalised: the weights on the surface.
  const Eigen::Vector3d corrected(w(0) / p0.z(), w(1) / p1.z(), w(2) / p2.z());
  const double sum = corrected.sum();
  if (std::abs(sum) < 1e-15) return Eigen::Vector3d::Constant(1.0 / 3.0);
  return corrected / sum;
}

Eigen::Vector3f sampleBilinear(const cv::Mat3b& image, double x, double y) {
  x = std::clamp(x, 0.0, image.cols - 1.0);
  y = std::clamp(y, 0.0, image.rows - 1.0);
  const int x0 = std::min(static_cast<int>(x), std::max(0, image.cols - 2));
  const int y0 = std::min(static_cast<int>(y), std::max(0, image.rows - 2));
  const int x1 = std::min(x0 + 1, image.cols - 1), y1 = std::min(y0 + 1, image.rows - 1);
  const float fx = static_cast<float>(x - x0), fy = static_cast<float>(y - y0);
  const cv::Vec3b &a = image(y0, x0), &b = image(y0, x1), &c = image(y1, x0), &d = image(y1, x1);
  Eigen::Vector3f out;
  for (int k = 0; k < 3; ++k) {
    out(k) =
        (1 - fx) * (1 - fy) * a[k] + fx * (1 - fy) * b[k] + (1 - fx) * fy * c[k] + fx * fy * d[k];
  }
  return out;
}

}  // namespace auv::recon::texture
