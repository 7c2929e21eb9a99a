#include "auv/sim/world/hull_contact.h"

#include <algorithm>
#include <cmath>

namespace auv::sim {

std::optional<HullContact> findHullContact(const RayCaster& world, double seabed_depth,
                                           const HullShape& hull,
                                           const Eigen::Isometry3d& body_pose) {
  const double half_axis = std::max(0.0, hull.length / 2 - hull.radius);
  const Eigen::Vector3d a = body_pose * Eigen::Vector3d(half_axis, 0, 0);
  const Eigen::Vector3d b = body_pose * Eigen::Vector3d(-half_axis, 0, 0);
  const Eigen::Vector3d ab = b - a;
  const auto distanceToAxis = [&](const Eigen::Vector3d& q, Eigen::Vector3d& on_axis) {
    const double len2 = ab.squaredNorm();
    const double s = len2 > 0 ? std::clamp((q - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    on_axis = a + s * ab;
    return (q - on_axis).norm();
  };

  std::optional<HullContact> best;
  // Closest-point queries from points along the axis, spaced at most r/2: a mesh point within
  // r of the axis is then within 1.03 r of a sample, so a search radius of 1.1 r finds it.
  const int samples = std::max(2, static_cast<int>(std::ceil(ab.norm() / (hull.radius / 2))) + 1);
  for (int i = 0; i < samples; ++i) {
    const Eigen::Vector3d p = a + ab * (static_cast<double>(i) / (samples - 1));
    Eigen::Vector3f closest;
    uint32_t triangle = RayHit::kNoHit;
    if (!world.closestPoint(p.cast<float>(), static_cast<float>(1.1 * hull.radius), closest,
                            triangle)) {
      continue;
    }
    const Eigen::Vector3d q = closest.cast<double>();
    Eigen::Vector3d on_axis;
    const double d = distanceToAxis(q, on_axis);
    const double penetration = hull.radius - d;
    if (penetration <= 0 || (best && best->penetration >= penetration)) continue;
    HullContact c;
    c.point = q;
    c.normal = d > 1e-9 ? Eigen::Vector3d((on_axis - q) / d) : Eigen::Vector3d(0, 0, -1);
    c.penetration = penetration;
    c.triangle = triangle;
    best = c;
  }
  // The flat seabed beyond the mesh: the lowest point of the capsule.
  const double lowest = std::max(a.z(), b.z()) + hull.radius;
  if (lowest > seabed_depth && (!best || lowest - seabed_depth > best->penetration)) {
    HullContact c;
    const Eigen::Vector3d& deepest_end = a.z() > b.z() ? a : b;
    c.point = Eigen::Vector3d(deepest_end.x(), deepest_end.y(), seabed_depth);
    c.normal = Eigen::Vector3d(0, 0, -1);
    c.penetration = lowest - seabed_depth;
    best = c;
  }
  return best;
}

double hullClearance(const RayCaster& world, double seabed_depth, const HullShape& hull,
                     const Eigen::Isometry3d& body_pose, double max_distance) {
  const double half_axis = std::max(0.0, hull.length / 2 - hull.radius);
  const Eigen::Vector3d a = body_pose * Eigen::Vector3d(half_axis, 0, 0);
  const Eigen::Vector3d b = body_pose * Eigen::Vector3d(-half_axis, 0, 0);
  double nearest = max_distance + hull.radius;  // from the axis
  constexpr int kSamples = 5;
  for (int i = 0; i < kSamples; ++i) {
    const Eigen::Vector3d p = a + (b - a) * (static_cast<double>(i) / (kSamples - 1));
    Eigen::Vector3f closest;
    uint32_t triangle = RayHit::kNoHit;
    if (world.closestPoint(p.cast<float>(), static_cast<float>(nearest), closest, triangle)) {
      nearest = std::min(nearest, (closest.cast<double>() - p).norm());
    }
  }
  nearest = std::min(nearest, seabed_depth - std::max(a.z(), b.z()));
  return std::min(max_distance, nearest - hull.radius);
}

}  // namespace auv::sim
