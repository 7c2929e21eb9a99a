#pragma once
// Contacts between the vehicle's hull, modelled as a capsule along the body x axis, and the
// world: the true mesh plus the flat seabed beyond it. This is the simulator's ground truth for
// every safety check (a planner that "never collides" is judged by it).

#include <Eigen/Geometry>
#include <optional>

#include "auv/sim/raycast/ray_caster.h"

namespace auv::sim {

struct HullShape {
  double length = 1.6;    ///< m, overall length (tip to tip)
  double radius = 0.115;  ///< m
};

struct HullContact {
  Eigen::Vector3d point;               ///< m NED, point of the world touching (inside) the hull
  Eigen::Vector3d normal;              ///< unit, from the world towards the hull axis
  double penetration = 0.0;            ///< m, radius minus the point's distance to the axis, > 0
  uint32_t triangle = RayHit::kNoHit;  ///< mesh triangle, or kNoHit for the flat seabed
};

/// The deepest contact of the hull at `body_pose` (body FRD -> world NED), if any.
/// `seabed_depth` is the flat seabed beyond the mesh (m NED z).
std::optional<HullContact> findHullContact(const RayCaster& world, double seabed_depth,
                                           const HullShape& hull,
                                           const Eigen::Isometry3d& body_pose);

/// Distance from the hull surface at `body_pose` to the world (mesh or flat seabed), capped at
/// `max_distance`; <= 0 in contact. Measured from 5 points along the axis, so it may
/// overestimate by a few centimetres between them: a figure for reports, not for contacts.
double hullClearance(const RayCaster& world, double seabed_depth, const HullShape& hull,
                     const Eigen::Isometry3d& body_pose, double max_distance);

}  // namespace auv::sim
