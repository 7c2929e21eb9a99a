#pragma once
// A lumpy closed rock to place on a world (a block fallen since the last visit, debris).

#include <Eigen/Core>

#include "auv/sim/world/mesh.h"

namespace auv::sim {

/// A closed rock of the given length, width and height (m) whose base centre sits at `base`
/// (NED: the rock rises towards -z), sunk 10 % of its height into the surface below, turned
/// `yaw_deg` about the vertical, its outline made lumpy by `seed`. Painted like `world`: with
/// `world`'s texture (texture coordinates laid over the texels of `world`'s triangle nearest
/// to `base`, at that triangle's texel size), else its vertex colours, else mid grey.
Mesh makeRock(const Eigen::Vector3d& base, const Eigen::Vector3d& size, double yaw_deg, int seed,
              const Mesh& world);

}  // namespace auv::sim
