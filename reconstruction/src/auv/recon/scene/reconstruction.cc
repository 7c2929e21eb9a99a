#include "auv/recon/scene/reconstruction.h"

#include <limits>
#include <stdexcept>
#include <string>

namespace auv::recon::scene {

Eigen::Isometry3d Image::worldToCamera() const {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = rotation();
  pose.translation() = t_cw;
  return pose;
}

void Image::setWorldToCamera(const Eigen::Isometry3d& pose) {
  q_cw = Eigen::Quaterniond(pose.linear()).normalized();
  t_cw = pose.translation();
}

size_t Image::numPoints3D() const {
  size_t n = 0;
  for (int64_t id : point3d_ids) n += id != kNoPoint3D;
  return n;
}

const Camera& Reconstruction::cameraOf(const Image& image) const {
  auto it = cameras.find(image.camera_id);
  if (it == cameras.end()) {
    throw std::out_of_range("image " + std::to_string(image.id) + " ('" + image.name +
                            "') refers to camera " + std::to_string(image.camera_id) +
                            ", which is not in the reconstruction");
  }
  return it->second;
}

double Reconstruction::reprojectionError(const Point3D& point,
                                         const TrackElement& observation) const {
  const Image& image = images.at(observation.image_id);
  const Eigen::Vector3d p = image.toCamera(point.xyz);
  if (p.z() <= 0) return std::numeric_limits<double>::infinity();
  return (cameraOf(image).project(p) - image.points2d.at(observation.point2d_idx)).norm();
}

double Reconstruction::meanReprojectionError() const {
  double sum = 0;
  size_t n = 0;
  for (const auto& [id, point] : points) {
    for (const auto& observation : point.track) {
      sum += reprojectionError(point, observation);
      ++n;
    }
  }
  return n > 0 ? sum / n : 0.0;
}

double Reconstruction::meanTrackLength() const {
  return points.empty() ? 0.0 : static_cast<double>(numObservations()) / points.size();
}

size_t Reconstruction::numObservations() const {
  size_t n = 0;
  for (const auto& [id, point] : points) n += point.track.size();
  return n;
}

void Reconstruction::updatePointErrors() {
  for (auto& [id, point] : points) {
    double sum = 0;
    for (const auto& observation : point.track) sum += reprojectionError(point, observation);
    point.error = point.track.empty() ? 0.0 : sum / point.track.size();
  }
}

void Reconstruction::checkConsistency() const {
  for (const auto& [id, image] : images) {
    cameraOf(image);
    if (image.point3d_ids.size() != image.points2d.size()) {
      throw std::runtime_error("image " + std::to_string(id) + ": " +
                               std::to_string(image.points2d.size()) + " keypoints but " +
                               std::to_string(image.point3d_ids.size()) + " point ids");
    }
    for (size_t k = 0; k < image.point3d_ids.size(); ++k) {
      const int64_t pid = image.point3d_ids[k];
      if (pid == kNoPoint3D) continue;
      auto it = points.find(static_cast<uint64_t>(pid));
      if (it == points.end()) {
        throw std::runtime_error("image " + std::to_string(id) + " keypoint " + std::to_string(k) +
                                 " refers to missing point " + std::to_string(pid));
      }
    }
  }
  for (const auto& [id, point] : points) {
    for (const auto& e : point.track) {
      auto it = images.find(e.image_id);
      if (it == images.end() || e.point2d_idx >= it->second.point3d_ids.size() ||
          it->second.point3d_ids[e.point2d_idx] != static_cast<int64_t>(id)) {
        throw std::runtime_error("point " + std::to_string(id) + ": track element (image " +
                                 std::to_string(e.image_id) + ", keypoint " +
                                 std::to_string(e.point2d_idx) + ") does not refer back to it");
      }
    }
  }
}

}  // namespace auv::recon::scene
