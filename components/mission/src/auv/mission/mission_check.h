#pragma once
// Checks of a mission against what the vehicle knows: the occupancy map built so far and the
// vehicle's depth limit. A mission that fails them is refused before anything moves.

#include <optional>
#include <string>
#include <vector>

#include <octomap/OcTree.h>

#include "auv/config/option_table.h"
#include "auv/mission/mission_plan.h"

namespace auv::mission {

struct MissionLimits {
  /// m, deepest depth the vehicle may be commanded to (the controller's max_depth).
  double max_depth = 50.0;
  /// m, the planner's clearance (hull radius + safety margin): a goal closer than this to a
  /// known occupied cell cannot be reached.
  double goal_clearance = 1.2;
  /// The fields with meaning, unit and range (the mission component's parameters of those
  /// names).
  static const config::OptionTable<MissionLimits>& table();
};

/// Throws MissionError naming `source`, the query and the reason when a goal (or the plane of a
/// fixed-depth query, or the depth band's max_depth) is deeper than max_depth, or when, on
/// `map` (may be null: no map yet), a goal lies within goal_clearance of an occupied cell, is
/// below the seabed (belowSeabed(); 3-D queries only), or has known seabed less than min_altitude +
/// goal_clearance below it (the planner would refuse it). `vehicle_depth` fills in unset plane
/// depths.
void checkAgainstVehicle(const std::vector<MissionQuery>& queries, const octomap::OcTree* map,
                         double vehicle_depth, const MissionLimits& limits,
                         const std::string& source);

/// Whether `point` is under the seabed: looking up its column (z decreasing, to the surface),
/// the first known cell is occupied. Open water seen between the point and rock above (the
/// space under an overhang or arch) is not under the seabed; unknown cells are skipped (inside
/// rock nothing is ever seen). Returns the depth of that rock's underside when it is.
std::optional<double> belowSeabed(const octomap::OcTree& map, const Eigen::Vector3d& point);
/// m, vertical distance from `point` down to the top of the nearest known occupied cell of its
/// column within `reach` (infinity when none): the planner's min_altitude measure.
double altitudeOverSeabed(const octomap::OcTree& map, const Eigen::Vector3d& point, double reach);

/// Distance from `point` to the centre of the nearest occupied cell of `map` within `radius`,
/// or a value > radius when there is none.
double distanceToOccupied(const octomap::OcTree& map, const Eigen::Vector3d& point, double radius);

}  // namespace auv::mission
