#pragma once
// Small synthetic scenes with known geometry for the dense tests: a textured slanted ground
// plane with a sphere standing on it, seen by posed pinhole cameras from above. Images are
// ray-cast with 3x3 supersampling; the true depth of every pixel centre is known.

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <random>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "auv/recon/dense/view.h"
#include "auv/recon/scene/reconstruction.h"

namespace auv::recon::dense::testing {

struct Scene {
  Eigen::Vector3d plane_normal = Eigen::Vector3d(-0.1, -0.05, 1.0).normalized();  // n.x = 0
  bool with_sphere = true;
  Eigen::Vector3d sphere_center{0.3, 0.2, 0.2};
  double sphere_radius = 0.6;
  bool textured = true;        ///< false: a flat grey world (nothing to match)
  double texture_scale = 1.0;  ///< multiplies the texture's feature sizes (4 to 16 cm at 1)

  /// Nearest hit along the ray, or a negative distance.
  double intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const {
    double best = -1;
    const double denominator = plane_normal.dot(direction);
    if (std::abs(denominator) > 1e-12) {
      const double t = -plane_normal.dot(origin) / denominator;
      if (t > 0) best = t;
    }
    if (with_sphere) {
      const Eigen::Vector3d oc = origin - sphere_center;
      const double b = oc.dot(direction), c = oc.squaredNorm() - sphere_radius * sphere_radius;
      const double disc = b * b - c;
      if (disc >= 0) {
        const double t = -b - std::sqrt(disc);
        if (t > 0 && (best < 0 || t < best)) best = t;
      }
    }
    return best;
  }

  /// Value noise in 3D, 0..1.
  static double hash(int x, int y, int z) {
    uint32_t h = static_cast<uint32_t>(x) * 73856093u ^ static_cast<uint32_t>(y) * 19349663u ^
                 static_cast<uint32_t>(z) * 83492791u;
    h ^= h >> 13;
    h *= 0x5bd1e995u;
    h ^= h >> 15;
    return (h & 0xffffff) / static_cast<double>(0xffffff);
  }
  static double noise(const Eigen::Vector3d& p) {
    const Eigen::Vector3d f = p.array().floor();
    const int x = static_cast<int>(f.x()), y = static_cast<int>(f.y()), z = static_cast<int>(f.z());
    Eigen::Vector3d u = p - f;
    u = u.array() * u.array() * (3.0 - 2.0 * u.array());
    double value = 0;
    for (int dz = 0; dz < 2; ++dz) {
      for (int dy = 0; dy < 2; ++dy) {
        for (int dx = 0; dx < 2; ++dx) {
          const double w =
              (dx ? u.x() : 1 - u.x()) * (dy ? u.y() : 1 - u.y()) * (dz ? u.z() : 1 - u.z());
          value += w * hash(x + dx, y + dy, z + dz);
        }
      }
    }
    return value;
  }
  /// BGR colour of a surface point.
  Eigen::Vector3d color(const Eigen::Vector3d& p) const {
    if (!textured) return {128, 128, 128};
    const Eigen::Vector3d q = p / texture_scale;
    const double a = 0.5 * noise(q / 0.16) + 0.3 * noise(q / 0.08 + Eigen::Vector3d(7, 3, 1)) +
                     0.2 * noise(q / 0.04 + Eigen::Vector3d(1, 9, 4));
    const double b = noise(q / 0.3 + Eigen::Vector3d(5, 5, 5));
    const double grey = 30 + 200 * a;
    return {grey * (0.8 + 0.2 * b), grey, grey * (1.0 - 0.2 * b)};
  }
};

/// A camera looking straight down (camera z = world -z) from `center`, optionally tilted about
/// the world x axis by `tilt_deg`.
inline View downwardView(uint32_t id, const Eigen::Vector3d& center, int width, int height,
                         double focal, double tilt_deg = 0) {
  View view;
  view.image_id = id;
  view.camera_id = 1;
  view.name = "cam/image_" + std::to_string(id) + ".png";
  view.width = view.source_width = width;
  view.height = view.source_height = height;
  view.K << focal, 0, (width - 1) / 2.0, 0, focal, (height - 1) / 2.0, 0, 0, 1;
  Eigen::Matrix3d down;
  down << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  const Eigen::Matrix3d tilt =
      Eigen::AngleAxisd(tilt_deg * M_PI / 180.0, Eigen::Vector3d::UnitX()).toRotationMatrix();
  view.R = tilt * down;
  view.t = -view.R * center;
  return view;
}

/// Renders colour (and grey) into the view and returns the true depth of each pixel centre.
inline cv::Mat render(const Scene& scene, View& view) {
  cv::Mat depth(view.height, view.width, CV_32F, cv::Scalar(0));
  view.color = cv::Mat(view.height, view.width, CV_8UC3, cv::Scalar::all(0));
  const Eigen::Matrix3d k_inv = view.K.inverse();
  const Eigen::Vector3d origin = view.center();
  const Eigen::Matrix3d to_world = view.R.transpose();
#pragma omp parallel for schedule(dynamic, 8)
  for (int y = 0; y < view.height; ++y) {
    for (int x = 0; x < view.width; ++x) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (int sy = -1; sy <= 1; ++sy) {
        for (int sx = -1; sx <= 1; ++sx) {
          const Eigen::Vector3d ray_camera = k_inv * Eigen::Vector3d(x + sx / 3.0, y + sy / 3.0, 1);
          const Eigen::Vector3d direction = (to_world * ray_camera).normalized();
          const double t = scene.intersect(origin, direction);
          if (t > 0) sum += scene.color(origin + t * direction);
          if (sx == 0 && sy == 0 && t > 0) {
            depth.at<float>(y, x) = static_cast<float>(view.toCamera(origin + t * direction).z());
          }
        }
      }
      sum /= 9.0;
      view.color.at<cv::Vec3b>(y, x) =
          cv::Vec3b(cv::saturate_cast<uint8_t>(sum.x()), cv::saturate_cast<uint8_t>(sum.y()),
                    cv::saturate_cast<uint8_t>(sum.z()));
    }
  }
  cv::Mat grey;
  cv::cvtColor(view.color, grey, cv::COLOR_BGR2GRAY);
  grey.convertTo(view.grey, CV_32F);
  return depth;
}

/// Views on a grid of `columns` x `rows` centres `spacing` m apart at `height` m.
inline std::vector<View> gridViews(int columns, int rows, double spacing, double height,
                                   int width = 240, int image_height = 180, double focal = 220) {
  std::vector<View> views;
  uint32_t id = 1;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < columns; ++c) {
      const Eigen::Vector3d center((c - (columns - 1) / 2.0) * spacing,
                                   (r - (rows - 1) / 2.0) * spacing, height);
      views.push_back(downwardView(id++, center, width, image_height, focal));
    }
  }
  return views;
}

/// A sparse model of the views: points back-projected from a pixel grid of each view's true
/// depth, observed by every view that sees them (visible where the true depth agrees).
inline scene::Reconstruction sparseModel(const std::vector<View>& views,
                                         const std::vector<cv::Mat>& depths, int grid_px = 12) {
  scene::Reconstruction model;
  for (const View& view : views) {
    const double fx = view.K(0, 0), fy = view.K(1, 1), cx = view.K(0, 2), cy = view.K(1, 2);
    model.cameras[view.camera_id] =
        scene::Camera::pinhole(view.camera_id, view.width, view.height, fx, fy, cx, cy);
    scene::Image image;
    image.id = view.image_id;
    image.camera_id = view.camera_id;
    image.name = view.name;
    image.q_cw = Eigen::Quaterniond(view.R);
    image.t_cw = view.t;
    model.images[image.id] = image;
  }
  uint64_t next_id = 1;
  for (size_t v = 0; v < views.size(); ++v) {
    for (int y = grid_px / 2; y < views[v].height; y += grid_px) {
      for (int x = grid_px / 2 + static_cast<int>(v % 3) * 3; x < views[v].width; x += grid_px) {
        const double d = depths[v].at<float>(y, x);
        if (d <= 0) continue;
        scene::Point3D point;
        point.id = next_id++;
        point.xyz = views[v].backProject(x, y, d);
        for (size_t o = 0; o < views.size(); ++o) {
          const Eigen::Vector3d in_o = views[o].toCamera(point.xyz);
          if (in_o.z() <= 0) continue;
          const Eigen::Vector2d pixel = views[o].project(in_o);
          const int px = static_cast<int>(std::lround(pixel.x()));
          const int py = static_cast<int>(std::lround(pixel.y()));
          if (px < 0 || py < 0 || px >= views[o].width || py >= views[o].height) continue;
          if (std::abs(depths[o].at<float>(py, px) - in_o.z()) > 0.02 * in_o.z()) continue;
          scene::Image& image = model.images[views[o].image_id];
          point.track.push_back({image.id, static_cast<uint32_t>(image.points2d.size())});
          image.points2d.push_back(pixel);
          image.point3d_ids.push_back(static_cast<int64_t>(point.id));
        }
        if (point.track.size() >= 2) {
          model.points[point.id] = point;
        } else {
          for (const scene::TrackElement& e : point.track) {
            model.images[e.image_id].point3d_ids[e.point2d_idx] = scene::kNoPoint3D;
          }
        }
      }
    }
  }
  return model;
}

/// Writes each view's colour image under `folder / view.name`.
inline void writeImages(const std::vector<View>& views, const std::filesystem::path& folder) {
  for (const View& view : views) {
    const std::filesystem::path file = folder / view.name;
    std::filesystem::create_directories(file.parent_path());
    cv::imwrite(file.string(), view.color);
  }
}

}  // namespace auv::recon::dense::testing
