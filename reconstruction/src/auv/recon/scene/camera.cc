#include "auv/recon/scene/camera.h"

#include <Eigen/Dense>
#include <stdexcept>

namespace auv::recon::scene {

std::string cameraModelName(CameraModel model) {
  switch (model) {
    case CameraModel::SIMPLE_PINHOLE:
      return "SIMPLE_PINHOLE";
    case CameraModel::PINHOLE:
      return "PINHOLE";
    case CameraModel::OPENCV:
      return "OPENCV";
    case CameraModel::FULL_OPENCV:
      return "FULL_OPENCV";
  }
  return "?";
}

CameraModel cameraModelFromName(const std::string& name) {
  for (CameraModel m : {CameraModel::SIMPLE_PINHOLE, CameraModel::PINHOLE, CameraModel::OPENCV,
                        CameraModel::FULL_OPENCV}) {
    if (cameraModelName(m) == name) return m;
  }
  throw std::invalid_argument("camera model '" + name +
                              "' is not one of SIMPLE_PINHOLE, PINHOLE, OPENCV, FULL_OPENCV");
}

Camera Camera::pinhole(uint32_t id, int width, int height, double fx, double fy, double cx,
                       double cy) {
  Camera c;
  c.id = id;
  c.model = CameraModel::PINHOLE;
  c.width = width;
  c.height = height;
  c.fx = fx;
  c.fy = fy;
  c.cx = cx;
  c.cy = cy;
  return c;
}

Eigen::Matrix3d Camera::K() const {
  Eigen::Matrix3d k;
  k << fx, 0, cx, 0, fy, cy, 0, 0, 1;
  return k;
}

bool Camera::hasDistortion() const {
  for (double d : distortion) {
    if (d != 0.0) return true;
  }
  return false;
}

namespace {
/// OpenCV's distortion of normalised coordinates (rational model when 8 coefficients).
Eigen::Vector2d distort(const std::vector<double>& d, const Eigen::Vector2d& n) {
  if (d.empty()) return n;
  const double k1 = d[0], k2 = d.size() > 1 ? d[1] : 0, p1 = d.size() > 2 ? d[2] : 0,
               p2 = d.size() > 3 ? d[3] : 0, k3 = d.size() > 4 ? d[4] : 0,
               k4 = d.size() > 5 ? d[5] : 0, k5 = d.size() > 6 ? d[6] : 0,
               k6 = d.size() > 7 ? d[7] : 0;
  const double x = n.x(), y = n.y(), r2 = x * x + y * y, r4 = r2 * r2, r6 = r4 * r2;
  const double radial = (1 + k1 * r2 + k2 * r4 + k3 * r6) / (1 + k4 * r2 + k5 * r4 + k6 * r6);
  return {x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
          y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y};
}
}  // namespace

Eigen::Vector2d Camera::project(const Eigen::Vector3d& p) const {
  const Eigen::Vector2d d = distort(distortion, Eigen::Vector2d(p.x() / p.z(), p.y() / p.z()));
  return {fx * d.x() + cx, fy * d.y() + cy};
}

Eigen::Vector2d Camera::pixelToNormalized(const Eigen::Vector2d& pixel) const {
  const Eigen::Vector2d distorted((pixel.x() - cx) / fx, (pixel.y() - cy) / fy);
  if (!hasDistortion()) return distorted;
  // Fixed-point iteration as in OpenCV's undistortPoints, finished by Gauss-Newton steps.
  Eigen::Vector2d n = distorted;
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector2d residual = distort(distortion, n) - distorted;
    if (residual.squaredNorm() < 1e-24) break;
    Eigen::Matrix2d jacobian;
    const double h = 1e-7;
    for (int k = 0; k < 2; ++k) {
      Eigen::Vector2d step = n;
      step[k] += h;
      jacobian.col(k) = (distort(distortion, step) - distort(distortion, n)) / h;
    }
    n -= jacobian.partialPivLu().solve(residual);
  }
  return n;
}

bool Camera::inImage(const Eigen::Vector2d& pixel) const {
  return pixel.x() >= -0.5 && pixel.y() >= -0.5 && pixel.x() < width - 0.5 &&
         pixel.y() < height - 0.5;
}

}  // namespace auv::recon::scene
