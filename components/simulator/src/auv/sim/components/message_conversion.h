#pragma once
// Simulator values -> auv::msg messages (frames and units per idl/README.md).

#include <Eigen/Geometry>

#include "auv/msg/all.h"
#include "auv/sim/sensors/navigation.h"
#include "auv/sim/sensors/profiling_sonar.h"
#include "auv/sim/sensors/sensor_cloud.h"
#include "auv/sim/vehicle/vehicle.h"
#include "auv/sim/world/hull_contact.h"

namespace auv::sim {

/// Seconds (>= 0) -> msg::Time.
msg::Time toTime(double seconds);
double toSeconds(const msg::Time& time);
msg::Pose toPose(const Eigen::Isometry3d& pose);

/// `nav/odometry` from the navigation estimate.
msg::Odometry toOdometry(const NavigationEstimate& estimate);
/// `sim/ground_truth`: the true state, flagged GROUND_TRUTH, zero covariance.
msg::Odometry groundTruthOdometry(const VehicleState& state, double t, double altitude);
/// `sonar/beam` from one ping.
msg::SonarBeam toSonarBeam(const SonarPing& ping);
/// `sonar/scan` (multibeam) and `dvl/beams`: points in the body frame ("base_link"),
/// sensor_origin = the head's pose on the body.
msg::PointCloud toPointCloud(const SensorCloud& cloud);
/// `sim/collision`.
msg::CollisionEvent toCollisionEvent(const HullContact& contact, const VehicleState& state,
                                     double t, double speed, bool started);

}  // namespace auv::sim
