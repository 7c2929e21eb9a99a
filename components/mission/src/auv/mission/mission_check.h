#pragma once
// Checks of a mission against what the vehicle knows: the occupancy map built so far and the
// vehicle's depth limit. A mission that fails them is refused before anything moves.

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
/// fixed-depth query) is deeper than max_depth, or a goal lies within goal_clearance of an
/// occupied cell of `map` (may be null: no map yet). `vehicle_depth` fills in unset plane
/// depths.
void checkAgainstVehicle(const std::vector<MissionQuery>& queries, const octomap::OcTree* map,
                         double vehicle_depth, const MissionLimits& limits,
                         const std::string& source);

/// Distance from `point` to the centre of the nearest occupied cell of `map` within `radius`,
/// or a value > radius when there is none.
double distanceToOccupied(const octomap::OcTree& map, const Eigen::Vector3d& point, double radius);

}  // namespace auv::mission
