#include "auv/mission/mission_check.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace auv::mission {

const config::OptionTable<MissionLimits>& MissionLimits::table() {
  using config::Range;
  using O = MissionLimits;
  static const config::OptionTable<O> kTable = {
      {"max_depth", &O::max_depth, "deepest goal accepted (the controller's max_depth)", "m",
       Range::closed(0.1, 11000.0)},
      {"goal_clearance", &O::goal_clearance,
       "goals closer than this to a known occupied cell are refused (the planner's hull_radius "
       "+ safety_margin)",
       "m", Range::closed(0.0, 100.0)},
  };
  return kTable;
}

double distanceToOccupied(const octomap::OcTree& map, const Eigen::Vector3d& point, double radius) {
  double best = std::numeric_limits<double>::infinity();
  const octomap::point3d lo(point.x() - radius, point.y() - radius, point.z() - radius);
  const octomap::point3d hi(point.x() + radius, point.y() + radius, point.z() + radius);
  for (auto it = map.begin_leafs_bbx(lo, hi), end = map.end_leafs_bbx(); it != end; ++it) {
    if (!map.isNodeOccupied(*it)) continue;
    const octomap::point3d c = it.getCoordinate();
    // Distance to the cell's box, not its centre: a goal inside a coarse leaf is at 0.
    const double half = it.getSize() / 2;
    const Eigen::Vector3d centre(c.x(), c.y(), c.z());
    const Eigen::Vector3d outside =
        ((point - centre).cwiseAbs() - Eigen::Vector3d::Constant(half)).cwiseMax(0.0);
    best = std::min(best, outside.norm());
  }
  return best;
}

std::optional<double> belowSeabed(const octomap::OcTree& map, const Eigen::Vector3d& point) {
  octomap::OcTreeKey key;
  if (!map.coordToKeyChecked(octomap::point3d(point.x(), point.y(), point.z()), key)) {
    return std::nullopt;
  }
  const double half = map.getResolution() / 2;
  // Up the column (NED: z decreases upwards, as the keys do) from the point's own cell.
  for (octomap::key_type z = key[2];; --z) {
    octomap::OcTreeKey cell = key;
    cell[2] = z;
    const double centre = map.keyToCoord(z);
    if (centre + half < 0.0) break;  // above the surface
    if (const octomap::OcTreeNode* node = map.search(cell)) {
      if (map.isNodeOccupied(node)) return centre + half;
      return std::nullopt;  // open water seen above the point
    }
    if (z == 0) break;
  }
  return std::nullopt;
}

double altitudeOverSeabed(const octomap::OcTree& map, const Eigen::Vector3d& point, double reach) {
  constexpr double kNone = std::numeric_limits<double>::infinity();
  octomap::OcTreeKey key;
  if (!map.coordToKeyChecked(octomap::point3d(point.x(), point.y(), point.z()), key)) return kNone;
  const double half = map.getResolution() / 2;
  for (octomap::key_type z = key[2];; ++z) {
    octomap::OcTreeKey cell = key;
    cell[2] = z;
    const double top = map.keyToCoord(z) - half;
    if (top - point.z() > reach) break;
    const octomap::OcTreeNode* node = map.search(cell);
    if (node != nullptr && map.isNodeOccupied(node)) return std::max(0.0, top - point.z());
    if (z == std::numeric_limits<octomap::key_type>::max()) break;
  }
  return kNone;
}

void checkAgainstVehicle(const std::vector<MissionQuery>& queries, const octomap::OcTree* map,
                         double vehicle_depth, const MissionLimits& limits,
                         const std::string& source) {
  for (const MissionQuery& q : queries) {
    Eigen::Vector3d goal = q.goal;
    if (q.fixed_depth) goal.z() = q.depth ? *q.depth : vehicle_depth;
    const std::string context = source + ": query '" + q.name + "' goal";
    std::ostringstream where;
    where.precision(4);
    where << " (" << goal.x() << ", " << goal.y() << ", " << goal.z() << ")";
    if (goal.z() > limits.max_depth) {
      std::ostringstream why;
      why << context << where.str() << " is deeper than the vehicle's max_depth "
          << limits.max_depth << " m: unreachable depth";
      throw MissionError(why.str());
    }
    if (q.max_depth && *q.max_depth > limits.max_depth) {
      std::ostringstream why;
      why << source << ": query '" << q.name << "' max_depth: the band reaches " << *q.max_depth
          << " m, deeper than the vehicle's max_depth " << limits.max_depth << " m";
      throw MissionError(why.str());
    }
    if (map == nullptr) continue;
    const double distance = distanceToOccupied(*map, goal, limits.goal_clearance);
    if (distance < limits.goal_clearance) {
      std::ostringstream why;
      why.precision(3);
      why << context << where.str()
          << (distance == 0.0 ? " is inside a known obstacle" : " is too close to a known obstacle")
          << " (" << distance << " m from occupied space; the planner keeps "
          << limits.goal_clearance << " m)";
      throw MissionError(why.str());
    }
    // 3-D queries only: a fixed-depth plane is the paper's 2-D mode, unchanged.
    const std::optional<double> rock = q.fixed_depth ? std::nullopt : belowSeabed(*map, goal);
    if (rock) {
      std::ostringstream why;
      why.precision(4);
      why << context << where.str() << " is below the seabed: known rock at " << *rock
          << " m depth above it and no open water seen between";
      throw MissionError(why.str());
    }
    // The planner keeps min_altitude of water under its clearance sphere (map_validity.h).
    const double reach = q.min_altitude + limits.goal_clearance;
    const double altitude = q.min_altitude > 0.0 ? altitudeOverSeabed(*map, goal, reach)
                                                 : std::numeric_limits<double>::infinity();
    if (altitude < reach) {
      std::ostringstream why;
      why.precision(3);
      why << context << where.str() << " is " << altitude
          << " m above known seabed; the query keeps min_altitude " << q.min_altitude
          << " m + the planner's " << limits.goal_clearance << " m clearance";
      throw MissionError(why.str());
    }
  }
}

}  // namespace auv::mission
