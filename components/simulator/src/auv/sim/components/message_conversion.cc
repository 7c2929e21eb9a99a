#include "auv/sim/components/message_conversion.h"
#include "auv/interfaces/msg_eigen.h"
#include "auv/interfaces/msg_time.h"

#include <cmath>

namespace auv::sim {
namespace {

using interfaces::toPoint;
using interfaces::toVector3;

msg::Header header(double t, const char* frame) {
  msg::Header h;
  h.stamp(toTime(t));
  h.frame_id(frame);
  return h;
}

}  // namespace

msg::Time toTime(double seconds) { return interfaces::toMsgTime(std::llround(seconds * 1e9)); }

double toSeconds(const msg::Time& time) { return interfaces::toNanoseconds(time) * 1e-9; }

msg::Pose toPose(const Eigen::Isometry3d& pose) { return interfaces::toPose(pose); }

msg::Odometry toOdometry(const NavigationEstimate& estimate) {
  msg::Odometry odom;
  odom.header(header(estimate.stamp, "world"));
  odom.child_frame_id("base_link");
  odom.pose().pose(toPose(estimate.pose()));
  std::array<double, 36> pose_cov{}, twist_cov{};
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) {
      pose_cov[6 * r + c] = estimate.pose_covariance(r, c);
      twist_cov[6 * r + c] = estimate.twist_covariance(r, c);
    }
  }
  odom.pose().covariance(pose_cov);
  odom.twist().twist().linear(toVector3(estimate.velocity));
  odom.twist().twist().angular(toVector3(estimate.angular_velocity));
  odom.twist().covariance(twist_cov);
  odom.altitude(estimate.altitude);
  odom.source_flags(estimate.source_flags);
  return odom;
}

msg::Odometry groundTruthOdometry(const VehicleState& state, double t, double altitude) {
  msg::Odometry odom;
  odom.header(header(t, "world"));
  odom.child_frame_id("base_link");
  odom.pose().pose(toPose(state.pose()));
  odom.twist().twist().linear(toVector3({state.surge, state.sway, state.heave}));
  odom.twist().twist().angular(toVector3({0, 0, state.yaw_rate}));
  odom.altitude(altitude);
  odom.source_flags(msg::ODOMETRY_SOURCE_GROUND_TRUTH);
  return odom;
}

msg::SonarBeam toSonarBeam(const SonarPing& ping) {
  msg::SonarBeam beam;
  beam.header(header(ping.stamp, "sonar"));
  beam.mounting(toPose(ping.mounting));
  beam.beam_angle(static_cast<float>(ping.angle));
  beam.horizontal_beam_width(static_cast<float>(ping.horizontal_beam_width));
  beam.vertical_beam_width(static_cast<float>(ping.vertical_beam_width));
  beam.min_range(static_cast<float>(ping.min_range));
  beam.max_range(static_cast<float>(ping.max_range));
  beam.range_resolution(static_cast<float>(ping.range_resolution));
  beam.sound_speed(static_cast<float>(ping.sound_speed));
  beam.ranges(ping.ranges);
  beam.range_intensities(ping.intensities);
  beam.bins(ping.bins);
  beam.flags(ping.flags);
  return beam;
}

msg::PointCloud toPointCloud(const SensorCloud& cloud) {
  msg::PointCloud out;
  out.header(header(cloud.stamp, "base_link"));
  out.sensor_origin(toPose(cloud.mounting));
  out.max_range(static_cast<float>(cloud.max_range));
  out.points().resize(cloud.points.size());
  for (size_t i = 0; i < cloud.points.size(); ++i) {
    msg::PointXYZI& p = out.points()[i];
    p.x(cloud.points[i].x());
    p.y(cloud.points[i].y());
    p.z(cloud.points[i].z());
    p.intensity(i < cloud.intensities.size() ? cloud.intensities[i] : 0.0f);
  }
  return out;
}

msg::CollisionEvent toCollisionEvent(const HullContact& contact, const VehicleState& state,
                                     double t, double speed, bool started) {
  msg::CollisionEvent event;
  event.header(header(t, "world"));
  event.contact_point(toPoint(contact.point));
  event.contact_normal(toVector3(contact.normal));
  event.penetration(contact.penetration);
  event.speed(speed);
  event.vehicle_pose(toPose(state.pose()));
  event.face_index(contact.triangle);
  event.started(started);
  return event;
}

}  // namespace auv::sim
