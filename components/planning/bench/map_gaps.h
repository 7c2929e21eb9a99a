// The gaps of a row of structures (the breakwater's blocks) on a vehicle's own map beside their
// true width: why missions go round the row when the true map has a way through.
#pragma once

#include <optional>
#include <vector>

namespace octomap {
class OcTree;
}

namespace auv::planning::bench {

struct GapWidth {
  double centre = 0.0;      ///< m, y of the gap's centre on the true map
  double true_width = 0.0;  ///< m, free between the faces on the true map
  /// m, the narrowest free stretch of the own map across the gap (0 when closed somewhere);
  /// nullopt when the own map has no face on one side at any x (not measurable).
  std::optional<double> own_width;
};

/// The gaps are the free stretches of 1-6 m between occupied faces along y on `truth` at
/// x = row_x, depth z (the row runs along y, NED east). For each, the narrowest free stretch of
/// `own` across the gap's centre (±1 m) for x in [row_x - half_length, row_x + half_length],
/// 1 m apart, where the own map has faces on both sides: the room the planner sees (its
/// clearance counts from voxel boxes). Unknown counts as free; a voxel counts when it is
/// occupied within half a voxel of z (a horizontal profiler's map is one voxel thick).
std::vector<GapWidth> measureGaps(const octomap::OcTree& truth, const octomap::OcTree& own,
                                  double z, double row_x = 0.0, double half_length = 5.0);

}  // namespace auv::planning::bench
