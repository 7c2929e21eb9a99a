#include "auv/recon/sfm/alignment.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>
#include <Eigen/SVD>

namespace auv::recon::sfm {

std::optional<Similarity> estimateSimilarity(const std::vector<Eigen::Vector3d>& from,
                                             const std::vector<Eigen::Vector3d>& to,
                                             bool with_scale) {
  if (from.size() != to.size() || from.size() < 3) return std::nullopt;
  Eigen::Matrix3Xd a(3, from.size()), b(3, to.size());
  for (size_t i = 0; i < from.size(); ++i) {
    a.col(i) = from[i];
    b.col(i) = to[i];
  }
  // Collinear (or coincident) points leave a rotation about their line free.
  const Eigen::Matrix3Xd centred = a.colwise() - a.rowwise().mean();
  const Eigen::JacobiSVD<Eigen::Matrix3Xd> svd(centred);
  const Eigen::Vector3d sv = svd.singularValues();
  if (!(sv(0) > 0) || sv(1) < 1e-9 * sv(0)) return std::nullopt;
  const Eigen::Matrix4d t = Eigen::umeyama(a, b, with_scale);
  if (!t.allFinite()) return std::nullopt;
  Similarity s;
  s.scale = with_scale ? std::cbrt(t.topLeftCorner<3, 3>().determinant()) : 1.0;
  s.rotation = t.topLeftCorner<3, 3>() / s.scale;
  s.translation = t.topRightCorner<3, 1>();
  return s;
}

void transformReconstruction(const Similarity& s, scene::Reconstruction& reconstruction) {
  for (auto& [id, point] : reconstruction.points) point.xyz = s.apply(point.xyz);
  for (auto& [id, image] : reconstruction.images) {
    const Eigen::Vector3d center = s.apply(image.center());
    const Eigen::Matrix3d r = image.rotation() * s.rotation.transpose();
    image.q_cw = Eigen::Quaterniond(r).normalized();
    image.t_cw = -(r * center);
  }
}

std::optional<PoseErrors> poseErrorsAfterAlignment(
    const std::map<uint32_t, scene::Image>& estimated,
    const std::map<uint32_t, scene::Image>& reference) {
  std::vector<Eigen::Vector3d> from, to;
  std::vector<uint32_t> ids;
  for (const auto& [id, image] : estimated) {
    auto it = reference.find(id);
    if (it == reference.end()) continue;
    from.push_back(image.center());
    to.push_back(it->second.center());
    ids.push_back(id);
  }
  const std::optional<Similarity> s = estimateSimilarity(from, to);
  if (!s) return std::nullopt;
  PoseErrors errors;
  errors.alignment = *s;
  errors.images = ids.size();
  // Rotation alignment A minimising sum |R_est A^T - R_ref|: the projection onto SO(3) of
  // the sum of R_ref^T R_est.
  Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
  for (uint32_t id : ids)
    sum += reference.at(id).rotation().transpose() * estimated.at(id).rotation();
  Eigen::JacobiSVD<Eigen::Matrix3d> rsvd(sum, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (rsvd.matrixU() * rsvd.matrixV().transpose()).determinant() < 0 ? -1 : 1;
  const Eigen::Matrix3d align = rsvd.matrixU() * d * rsvd.matrixV().transpose();
  std::vector<double> distances;
  for (size_t i = 0; i < ids.size(); ++i) {
    const double d = (s->apply(from[i]) - to[i]).norm();
    distances.push_back(d);
    errors.mean_position += d / ids.size();
    errors.max_position = std::max(errors.max_position, d);
    const Eigen::Matrix3d r_est = estimated.at(ids[i]).rotation() * align.transpose();
    const Eigen::Matrix3d delta = r_est * reference.at(ids[i]).rotation().transpose();
    const double angle = std::acos(std::clamp((delta.trace() - 1) / 2, -1.0, 1.0)) * 180.0 / M_PI;
    errors.mean_rotation_deg += angle / ids.size();
    errors.max_rotation_deg = std::max(errors.max_rotation_deg, angle);
  }
  std::nth_element(distances.begin(), distances.begin() + distances.size() / 2, distances.end());
  errors.median_position = distances[distances.size() / 2];
  return errors;
}

}  // namespace auv::recon::sfm
