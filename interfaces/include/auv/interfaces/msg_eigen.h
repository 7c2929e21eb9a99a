#pragma once
// Geometry messages <-> Eigen (frames and units per idl/README.md), one set for every component.
// Header-only: link auv_interfaces::auv_interfaces_eigen (auv_interfaces + Eigen3::Eigen), or
// Eigen3::Eigen beside auv_interfaces.

#include <Eigen/Geometry>

#include "auv/msg/all.h"

namespace auv::interfaces {

inline Eigen::Vector3d toEigen(const msg::Point& p) { return {p.x(), p.y(), p.z()}; }
inline Eigen::Vector3d toEigen(const msg::Vector3& v) { return {v.x(), v.y(), v.z()}; }

/// The orientation as a unit quaternion; an unset (all-zero) one is the identity.
inline Eigen::Quaterniond toEigen(const msg::Quaternion& q) {
  Eigen::Quaterniond result(q.w(), q.x(), q.y(), q.z());
  if (result.norm() < 1e-9) return Eigen::Quaterniond::Identity();
  return result.normalized();
}

/// world_T_body of a pose; an unset orientation is the identity.
inline Eigen::Isometry3d toIsometry(const msg::Pose& pose) {
  Eigen::Isometry3d result = Eigen::Isometry3d::Identity();
  result.translation() = toEigen(pose.position());
  result.linear() = toEigen(pose.orientation()).toRotationMatrix();
  return result;
}

inline msg::Point toPoint(const Eigen::Vector3d& v) {
  msg::Point p;
  p.x(v.x());
  p.y(v.y());
  p.z(v.z());
  return p;
}

inline msg::Vector3 toVector3(const Eigen::Vector3d& v) {
  msg::Vector3 out;
  out.x(v.x());
  out.y(v.y());
  out.z(v.z());
  return out;
}

inline msg::Quaternion toQuaternion(const Eigen::Quaterniond& q) {
  msg::Quaternion out;
  out.x(q.x());
  out.y(q.y());
  out.z(q.z());
  out.w(q.w());
  return out;
}

inline msg::Pose toPose(const Eigen::Isometry3d& pose) {
  msg::Pose out;
  out.position(toPoint(pose.translation()));
  out.orientation(toQuaternion(Eigen::Quaterniond(pose.linear())));
  return out;
}

}  // namespace auv::interfaces
