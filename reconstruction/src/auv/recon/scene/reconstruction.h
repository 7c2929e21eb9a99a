#pragma once
// A sparse reconstruction: cameras, posed images with their keypoints, 3D points with tracks.
// What SfM produces and the dense, mesh, texture and evaluate stages read (through the COLMAP
// text files of colmap_text.h).

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "auv/recon/scene/camera.h"

namespace auv::recon::scene {

/// No 3D point for this keypoint.
constexpr int64_t kNoPoint3D = -1;

struct Image {
  uint32_t id = 0;
  uint32_t camera_id = 0;
  /// Path relative to the image folder, e.g. "left/left_0001_000123.png".
  std::string name;
  /// World -> camera: x_camera = q_cw * x_world + t_cw.
  Eigen::Quaterniond q_cw = Eigen::Quaterniond::Identity();
  Eigen::Vector3d t_cw = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector2d> points2d;  ///< px, OpenCV convention
  std::vector<int64_t> point3d_ids;       ///< per keypoint, kNoPoint3D when none

  Eigen::Matrix3d rotation() const { return q_cw.toRotationMatrix(); }
  /// Camera centre in the world frame.
  Eigen::Vector3d center() const { return -(q_cw.conjugate() * t_cw); }
  /// Direction of the optical axis (camera z) in the world frame.
  Eigen::Vector3d viewDirection() const { return q_cw.conjugate() * Eigen::Vector3d::UnitZ(); }
  Eigen::Vector3d toCamera(const Eigen::Vector3d& world) const { return q_cw * world + t_cw; }
  Eigen::Isometry3d worldToCamera() const;
  void setWorldToCamera(const Eigen::Isometry3d& pose);
  size_t numPoints3D() const;
};

struct TrackElement {
  uint32_t image_id = 0;
  uint32_t point2d_idx = 0;
  bool operator==(const TrackElement& o) const {
    return image_id == o.image_id && point2d_idx == o.point2d_idx;
  }
};

struct Point3D {
  uint64_t id = 0;
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  Eigen::Matrix<uint8_t, 3, 1> rgb = Eigen::Matrix<uint8_t, 3, 1>::Zero();
  double error = 0;  ///< mean reprojection error over the track, px
  std::vector<TrackElement> track;
};

class Reconstruction {
 public:
  std::map<uint32_t, Camera> cameras;
  std::map<uint32_t, Image> images;  ///< registered (posed) images
  std::map<uint64_t, Point3D> points;

  /// The camera of an image; throws std::out_of_range naming the ids when missing.
  const Camera& cameraOf(const Image& image) const;
  /// Reprojection error of one observation, px.
  double reprojectionError(const Point3D& point, const TrackElement& observation) const;
  /// Mean over all observations, px (0 without points).
  double meanReprojectionError() const;
  double meanTrackLength() const;
  size_t numObservations() const;
  /// Recomputes every point's `error` from its track.
  void updatePointErrors();
  /// Checks the cross references (track <-> point3d_ids, camera ids); throws
  /// std::runtime_error naming the first inconsistency.
  void checkConsistency() const;
};

}  // namespace auv::recon::scene
