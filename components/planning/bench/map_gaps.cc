#include "map_gaps.h"

#include <algorithm>
#include <cmath>

#include <octomap/OcTree.h>

namespace auv::planning::bench {
namespace {

constexpr double kStep = 0.05;            // m, scan step along y
constexpr double kMinGap = 1.0;           // m, narrower free stretches are not gaps
constexpr double kMaxGap = 6.0;           // m, wider ones are open water or a block's inside
constexpr double kCentreSlack = 1.0;      // m, an own-map stretch must overlap the centre ± this
constexpr double kSearchHalfWidth = 8.0;  // m, own-map scan around the gap centre

struct Stretch {
  double from;  // m, y
  double to;    // m, y
};

/// Occupied within half a voxel of depth z: a horizontal profiler's map is one voxel thick,
/// and the plane's depth may lie on a voxel boundary.
bool occupiedAt(const octomap::OcTree& map, double x, double y, double z) {
  const double half = 0.5 * map.getResolution();
  for (const double dz : {0.0, -half + 1e-6, half - 1e-6}) {
    const octomap::OcTreeNode* node = map.search(x, y, z + dz);
    if (node != nullptr && map.isNodeOccupied(node)) return true;
  }
  return false;
}

/// Free stretches along y in [y0, y1] at (x, z), each bounded by occupied cells on both sides.
std::vector<Stretch> boundedFreeStretches(const octomap::OcTree& map, double x, double z, double y0,
                                          double y1) {
  std::vector<Stretch> stretches;
  double free_since = y0;
  bool in_free = false, seen_occupied = false;
  const int steps = static_cast<int>(std::floor((y1 - y0) / kStep));
  for (int i = 0; i <= steps; ++i) {
    const double y = y0 + i * kStep;
    if (occupiedAt(map, x, y, z)) {
      if (in_free && seen_occupied) stretches.push_back({free_since, y});
      in_free = false;
      seen_occupied = true;
    } else if (!in_free) {
      free_since = y;
      in_free = true;
    }
  }
  return stretches;
}

bool occupiedBetween(const octomap::OcTree& map, double x, double z, double y0, double y1) {
  for (double y = y0; y <= y1 + 1e-9; y += kStep) {
    if (occupiedAt(map, x, y, z)) return true;
  }
  return false;
}

}  // namespace

std::vector<GapWidth> measureGaps(const octomap::OcTree& truth, const octomap::OcTree& own,
                                  double z, double row_x, double half_length) {
  double x0, y0, z0, x1, y1, z1;
  // calcMinMax() is not const; the map's bounds do not change here.
  const_cast<octomap::OcTree&>(truth).getMetricMin(x0, y0, z0);
  const_cast<octomap::OcTree&>(truth).getMetricMax(x1, y1, z1);
  std::vector<GapWidth> gaps;
  for (const Stretch& gap : boundedFreeStretches(truth, row_x, z, y0, y1)) {
    GapWidth result;
    result.true_width = gap.to - gap.from;
    if (result.true_width <= kMinGap || result.true_width >= kMaxGap) continue;
    result.centre = 0.5 * (gap.from + gap.to);
    for (double x = row_x - half_length; x <= row_x + half_length + 1e-9; x += 1.0) {
      // Measurable where the own map has something on both sides of the centre.
      const double low = result.centre - kSearchHalfWidth, high = result.centre + kSearchHalfWidth;
      if (!occupiedBetween(own, x, z, low, result.centre) ||
          !occupiedBetween(own, x, z, result.centre, high)) {
        continue;
      }
      std::optional<double> widest_here;  // the own map's stretch across the centre
      for (const Stretch& s : boundedFreeStretches(own, x, z, low, high)) {
        if (s.from <= result.centre + kCentreSlack && s.to >= result.centre - kCentreSlack) {
          widest_here = std::max(widest_here.value_or(0.0), s.to - s.from);
        }
      }
      result.own_width = std::min(result.own_width.value_or(1e9), widest_here.value_or(0.0));
    }
    gaps.push_back(result);
  }
  return gaps;
}

}  // namespace auv::planning::bench
