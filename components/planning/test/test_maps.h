// Small maps shared by the tests: an OcTree with boxes of occupied cells, everything else
// unknown (free for the planner).
#pragma once

#include <memory>

#include <octomap/OcTree.h>
#include <ompl/base/ScopedState.h>

#include "auv/planning/distance_field.h"
#include "auv/planning/map_validity.h"

namespace auv::planning::testing {

constexpr double kResolution = 0.5;

/// Marks every cell whose centre lies in [min, max] as occupied (clamped log-odds).
inline void addOccupiedBox(octomap::OcTree& tree, const Eigen::Vector3d& min,
                           const Eigen::Vector3d& max) {
  const double half = 0.5 * kResolution;
  for (double x = min.x() + half; x <= max.x(); x += kResolution) {
    for (double y = min.y() + half; y <= max.y(); y += kResolution) {
      for (double z = min.z() + half; z <= max.z(); z += kResolution) {
        for (int i = 0; i < 4; ++i) tree.updateNode(octomap::point3d(x, y, z), true);
      }
    }
  }
}

/// A closed square ring (one cell thick, 2 m tall) around `centre` at `depth`, 3 m inside: a
/// goal inside it is valid but unreachable.
inline void addRing(octomap::OcTree& map, const Eigen::Vector3d& centre, double depth) {
  const double in = 3.0, out = 3.5, z0 = depth - 1.0, z1 = depth + 1.0;
  const double x = centre.x(), y = centre.y();
  addOccupiedBox(map, {x - out, y - out, z0}, {x - in, y + out, z1});
  addOccupiedBox(map, {x + in, y - out, z0}, {x + out, y + out, z1});
  addOccupiedBox(map, {x - out, y - out, z0}, {x + out, y - in, z1});
  addOccupiedBox(map, {x - out, y + in, z0}, {x + out, y + out, z1});
}

/// A 2-D world (fixed depth 5 m; 3-D over z in [0, 10] with three_d) x in [0, size], y in
/// [-size / 2, size / 2] (size 20 m unless set before build()), its map and planning space.
struct FlatWorld {
  std::unique_ptr<octomap::OcTree> tree = std::make_unique<octomap::OcTree>(kResolution);
  std::shared_ptr<OctomapDistanceField> field;
  ompl::base::SpaceInformationPtr si;
  ClearanceOptions clearance;
  double size = 20.0;
  bool three_d = false;  ///< plan in 3-D instead of the plane z = kDepth
  static constexpr double kDepth = 5.0;

  FlatWorld() {
    clearance.hull_radius = 0.6;
    clearance.safety_margin = 0.4;
  }
  /// Call after adding the initial obstacles.
  void build() {
    OctomapDistanceFieldOptions field_options;
    field_options.max_distance = 8.0;
    field_options.min_corner = {-2.0, -0.5 * size - 2.0, 0.0};
    field_options.max_corner = {size + 2.0, 0.5 * size + 2.0, 10.0};
    field = std::make_shared<OctomapDistanceField>(tree.get(), field_options);
    PlanningSpaceOptions space;
    space.min_corner = {0.0, -0.5 * size, 0.0};
    space.max_corner = {size, 0.5 * size, 10.0};
    if (!three_d) space.fixed_depth = kDepth;
    si = makeSpaceInformation(space, field, clearance);
  }
  ompl::base::ScopedState<> state(double x, double y, double z = kDepth) const {
    ompl::base::ScopedState<> s(si);
    s[0] = x;
    s[1] = y;
    s[2] = z;
    return s;
  }
};

}  // namespace auv::planning::testing
