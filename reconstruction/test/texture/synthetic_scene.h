#pragma once
// Synthetic texturing scenes with known answers: a terrain mesh whose true colour is a function
// of position, pinhole cameras looking down at it, and the images those cameras would take
// (ray-traced through the mesh's z-buffer), optionally with an exposure gain, noise and
// occluders floating in the water (fish) that are not part of the mesh.
#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include <opencv2/core.hpp>

#include "auv/recon/texture/rasterizer.h"
#include "auv/recon/texture/view_selection.h"

namespace synth {

using auv::recon::texture::FaceMesh;
using auv::recon::texture::ViewGeometry;

using Height = std::function<double(double, double)>;

/// Grid of (2 n) x (2 n) cells over [-extent, extent]^2, two triangles per cell, counter-
/// clockwise seen from above (normals up).
inline FaceMesh gridMesh(int n, double extent, const Height& height) {
  FaceMesh mesh;
  const int side = 2 * n + 1;
  for (int j = 0; j < side; ++j) {
    for (int i = 0; i < side; ++i) {
      const double x = -extent + extent * i / n, y = -extent + extent * j / n;
      mesh.vertices.emplace_back(x, y, height(x, y));
    }
  }
  for (int j = 0; j + 1 < side; ++j) {
    for (int i = 0; i + 1 < side; ++i) {
      const int a = j * side + i, b = a + 1, c = a + side, d = c + 1;
      mesh.faces.emplace_back(a, b, d);
      mesh.faces.emplace_back(a, d, c);
    }
  }
  mesh.computeFaceNormals();
  return mesh;
}

inline double flat(double, double) { return 0.0; }

/// The true colour of the sea floor (BGR, 0..255): smooth, with detail for the gradients.
inline Eigen::Vector3f trueColor(const Eigen::Vector3d& p) {
  const double x = p.x(), y = p.y(), z = p.z();
  return Eigen::Vector3f(
      static_cast<float>(110 + 50 * std::sin(3 * x + 1) * std::cos(2 * y) +
                         25 * std::sin(11 * x) * std::sin(9 * y)),
      static_cast<float>(130 + 45 * std::cos(2.5 * x - 0.5 * y) + 25 * std::sin(13 * y + 4 * x) +
                         30 * z),
      static_cast<float>(120 + 40 * std::sin(2 * y + 0.7) + 25 * std::cos(10 * x - 7 * y)));
}

/// A camera at `center` looking at `target` (image y axis towards -world y when looking down).
inline ViewGeometry lookAt(const Eigen::Vector3d& center, const Eigen::Vector3d& target,
                           int width = 160, int height = 120, double focal = 150) {
  const Eigen::Vector3d z = (target - center).normalized();
  Eigen::Vector3d up_hint =
      std::abs(z.y()) > 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d(0, -1, 0);
  const Eigen::Vector3d x = up_hint.cross(z).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d r_cw;
  r_cw.row(0) = x.transpose();
  r_cw.row(1) = y.transpose();
  r_cw.row(2) = z.transpose();
  ViewGeometry view;
  view.camera = auv::recon::scene::Camera::pinhole(1, width, height, focal, focal,
                                                   (width - 1) / 2.0, (height - 1) / 2.0);
  view.world_to_camera.linear() = r_cw;
  view.world_to_camera.translation() = -r_cw * center;
  return view;
}

struct Sphere {
  Eigen::Vector3d center;
  double radius;
};

/// The image `view` takes of the mesh's true colours, times `gain`, with Gaussian noise and
/// striped orange spheres (fish) in front of the sea floor.
inline cv::Mat3b renderTruth(const FaceMesh& mesh, const ViewGeometry& view, double gain = 1.0,
                             const std::vector<Sphere>& fish = {}, double noise = 0.0,
                             unsigned seed = 1) {
  using namespace auv::recon::texture;
  const RasterBuffers buffers = rasterize(mesh.vertices, mesh.faces, view);
  cv::Mat3b image(view.height(), view.width(), cv::Vec3b(60, 40, 20));
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, noise);
  const Eigen::Matrix3d r_wc = view.world_to_camera.linear().transpose();
  const Eigen::Vector3d center = view.center();
  for (int y = 0; y < view.height(); ++y) {
    for (int x = 0; x < view.width(); ++x) {
      Eigen::Vector3f color(60, 40, 20);
      double depth = std::numeric_limits<double>::infinity();
      const int f = buffers.face(y, x);
      if (f >= 0) {
        const Eigen::Vector3d w =
            barycentricAt(mesh.vertices, mesh.faces[f], view, Eigen::Vector2d(x, y));
        const Eigen::Vector3d p = w(0) * mesh.vertices[mesh.faces[f](0)] +
                                  w(1) * mesh.vertices[mesh.faces[f](1)] +
                                  w(2) * mesh.vertices[mesh.faces[f](2)];
        color = trueColor(p) * static_cast<float>(gain);
        depth = buffers.depth(y, x);
      }
      // Ray in the camera frame with z = 1: its parameter is the depth.
      const Eigen::Vector3d ray_c((x - view.camera.cx) / view.camera.fx,
                                  (y - view.camera.cy) / view.camera.fy, 1.0);
      const Eigen::Vector3d ray_w = r_wc * ray_c;
      for (const Sphere& s : fish) {
        const Eigen::Vector3d oc = center - s.center;
        const double a = ray_w.squaredNorm(), b = 2 * oc.dot(ray_w),
                     c = oc.squaredNorm() - s.radius * s.radius;
        const double disc = b * b - 4 * a * c;
        if (disc < 0) continue;
        const double t = (-b - std::sqrt(disc)) / (2 * a);
        if (t > 0 && t < depth) {
          depth = t;
          const Eigen::Vector3d p = center + t * ray_w;
          const bool stripe = std::fmod(std::abs(p.x() - s.center.x()) * 40.0, 2.0) < 1.0;
          color = stripe ? Eigen::Vector3f(20, 140, 250) : Eigen::Vector3f(240, 240, 240);
        }
      }
      for (int c = 0; c < 3; ++c) {
        image(y, x)[c] = cv::saturate_cast<uint8_t>(color(c) + (noise > 0 ? gauss(rng) : 0.0));
      }
    }
  }
  return image;
}

}  // namespace synth
