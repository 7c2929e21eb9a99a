#pragma once
// Message -> geometry conversions of the mapping component, in a header so that the benchmark
// places beams exactly as the component does (its maps are compared byte for byte).

#include <Eigen/Geometry>

#include "auv/interfaces/msg_eigen.h"
#include "auv/interfaces/msg_time.h"
#include "auv/mapping/map_builder.h"
#include "auv/mapping/pose_buffer.h"
#include "auv/msg/all.h"

namespace auv::mapping {

using interfaces::toIsometry;  // msg::Pose; an unset orientation is the identity

inline Eigen::Isometry3d toIsometry(const StampedPose& pose) {
  Eigen::Isometry3d result = Eigen::Isometry3d::Identity();
  result.translation() = pose.position;
  result.linear() = pose.orientation.toRotationMatrix();
  return result;
}

/// The pose buffer's entry for one odometry sample.
inline StampedPose toStampedPose(const msg::Odometry& odometry) {
  StampedPose pose;
  pose.stamp_ns = interfaces::toNanoseconds(odometry.header().stamp());
  const Eigen::Isometry3d world_T_body = toIsometry(odometry.pose().pose());
  pose.position = world_T_body.translation();
  pose.orientation = Eigen::Quaterniond(world_T_body.linear());
  return pose;
}

/// Beam geometry in the sonar head frame: the first echo within [min_range, max_range] is the
/// return (later echoes lie behind the first surface: multipath or weaker targets).
inline BeamGeometry toGeometry(const msg::SonarBeam& beam) {
  BeamGeometry geometry;
  geometry.direction = beamDirection(beam.beam_angle());
  geometry.min_range = beam.min_range();
  geometry.max_range = beam.max_range();
  for (float range : beam.ranges()) {
    if (range >= beam.min_range() && range <= beam.max_range()) {
      geometry.return_range = range;
      break;
    }
  }
  return geometry;
}

}  // namespace auv::mapping
