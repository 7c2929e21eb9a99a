#pragma once
// Small synthetic scenes and cameras shared by the camera tests.

#include <unistd.h>
#include <Eigen/Geometry>
#include <filesystem>
#include <string>
#include <vector>

#include "auv/sim/camera/camera_model.h"
#include "auv/sim/raycast/ray_caster.h"
#include "auv/sim/world/mesh.h"

namespace auv::sim::test {

/// A rectangle centred at `centre`, spanned by the unit axes `u` and `v` (half sizes in m),
/// with one sRGB vertex colour.
inline Mesh quadMesh(const Eigen::Vector3f& centre, const Eigen::Vector3f& u,
                     const Eigen::Vector3f& v, float half_u, float half_v,
                     const Eigen::Vector3f& srgb) {
  Mesh mesh;
  mesh.source = "test quad";
  mesh.vertices = {centre - half_u * u - half_v * v, centre + half_u * u - half_v * v,
                   centre + half_u * u + half_v * v, centre - half_u * u + half_v * v};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  mesh.vertex_colors.assign(4, srgb);
  return mesh;
}

/// A grey of linear albedo `albedo` as the sRGB vertex colour that gives it.
inline Eigen::Vector3f greySrgb(float albedo) {
  return Eigen::Vector3f::Constant(linearToSrgb(albedo));
}

/// Camera at `position` looking along world `forward` with image "down" as close to world
/// `down` as possible (OpenCV camera frame -> world NED).
inline Eigen::Isometry3d lookAlong(const Eigen::Vector3d& position, const Eigen::Vector3d& forward,
                                   const Eigen::Vector3d& down = Eigen::Vector3d::UnitZ()) {
  const Eigen::Vector3d z = forward.normalized();
  const Eigen::Vector3d x = down.cross(z).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = x;
  T.linear().col(1) = y;
  T.linear().col(2) = z;
  T.translation() = position;
  return T;
}

/// A small ideal test camera: no noise, vignetting or motion blur, exposure 1.
inline CameraOptions idealCamera(int width = 160, int height = 120) {
  CameraOptions camera = CameraOptions::defaults("test");
  camera.width = width;
  camera.height = height;
  camera.noise_sigma = 0;
  camera.vignetting = 0;
  camera.exposure_time = 0;
  camera.max_blur_samples = 1;
  return camera;
}

/// A fresh empty folder under the system temp folder, unique to this process (other builds may
/// run the same tests at the same time) and removed when the test program exits.
inline std::string freshFolder(const std::string& name) {
  struct Registry {
    std::vector<std::filesystem::path> paths;
    ~Registry() {
      std::error_code ignored;
      for (const auto& path : paths) std::filesystem::remove_all(path, ignored);
    }
  };
  static Registry registry;
  const auto path = std::filesystem::temp_directory_path() /
                    ("auv_camera_test_" + std::to_string(::getpid()) + "_" + name);
  std::filesystem::remove_all(path);
  std::filesystem::create_directories(path);
  registry.paths.push_back(path);
  return path.string();
}

}  // namespace auv::sim::test
