// The shortest collision-free path between two points on a FULLY KNOWN map at a clearance: the
// reference the benchmarks divide executed or planned path lengths by. Any-angle search (Lazy
// Theta*) on a regular grid, then line-of-sight shortcutting of the polyline; clearance comes
// from an exact Euclidean distance transform of the map's occupied voxels on that grid.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <vector>

#include <Eigen/Core>

namespace octomap {
class OcTree;
}

namespace auv::planning::bench {

/// Bad oracle options or queries (start or goal not free, outside the map).
class OracleError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

struct OracleOptions {
  /// m, required distance from a path point to the nearest occupied voxel centre.
  double clearance = 1.3;
  /// m, step of the search grid (and of the distance transform); best a multiple of the map
  /// resolution, so grid cells and voxels line up.
  double grid = 0.2;
  /// m, when set, paths stay in the horizontal plane at this depth (the planner's fixed depth).
  std::optional<double> fixed_depth;
  /// m, no path point above this depth (NED z; 0 = the sea surface).
  double min_depth = 0.0;
  /// m, when set, no path point below this depth (a mission's depth band; > min_depth).
  std::optional<double> max_depth;
  /// m, the searchable box is the map's known box grown by this much on every side, as free
  /// space: a vehicle's own map ends where its sonar saw (a horizontal profiler's map may be
  /// one voxel thick), and its start may lie just outside. >= 0.
  double padding = 0.0;

  /// Throws OracleError naming the field.
  void check() const;
};

struct OraclePath {
  bool found = false;
  double length = std::numeric_limits<double>::infinity();  ///< m
  std::vector<Eigen::Vector3d> points;                      ///< start, corners..., goal (NED)
  std::size_t expanded = 0;                                 ///< search nodes expanded
};

/// Rasterises the map once (occupied leaves; unknown counts as free, so give it a fully known
/// map, e.g. from `auv sim octomap`) and answers any number of queries. The searchable volume is
/// the map's known box (in fixed-depth mode its plane at the depth).
class ShortestPathOracle {
 public:
  /// Throws OracleError for bad options, an empty map or a depth outside the map.
  ShortestPathOracle(const octomap::OcTree& map, const OracleOptions& options);

  /// The shortest path start -> goal (in fixed-depth mode both are moved onto the plane).
  /// found = false when the goal cannot be reached. Throws OracleError when start or goal is
  /// outside the box or closer than the clearance to the map.
  OraclePath shortestPath(const Eigen::Vector3d& start, const Eigen::Vector3d& goal) const;

  /// The largest clearance (m, within `tolerance`) in [0, options().clearance] at which a path
  /// joins start and goal: the width of the bottleneck between them. The distance field does
  /// not depend on the clearance, so it is bisected on one raster. 0 when they are not joined
  /// even at 0 m, or lie outside the box. Leaves options().clearance as constructed.
  double bottleneckClearance(const Eigen::Vector3d& start, const Eigen::Vector3d& goal,
                             double tolerance = 0.01);

  /// m, distance to the nearest occupied voxel centre (trilinear between grid cells; 0 outside
  /// the grid). Exact at cell centres.
  double distance(const Eigen::Vector3d& position) const;
  /// Unit direction in which distance() grows fastest (zero where it is flat).
  Eigen::Vector3d distanceGradient(const Eigen::Vector3d& position) const;
  /// distance() >= clearance and inside the searchable volume.
  bool isFree(const Eigen::Vector3d& position) const;
  /// True when the straight segment a-b stays free.
  bool lineOfSight(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const;

  const OracleOptions& options() const { return options_; }
  Eigen::Vector3d minCorner() const { return min_corner_; }  ///< m, the searchable box
  Eigen::Vector3d maxCorner() const { return max_corner_; }

 private:
  using Index = std::int64_t;
  /// Grid cell -> distance array index; the caller keeps i, j, k in range.
  Index cellIndex(int i, int j, int k) const {
    return static_cast<Index>(i) +
           static_cast<Index>(size_[0]) * (j + static_cast<Index>(size_[1]) * k);
  }
  /// Search node -> position (in fixed-depth mode nodes are the cell columns at the depth).
  Eigen::Vector3d nodePosition(Index node) const;
  std::optional<Index> nodeAt(const Eigen::Vector3d& position) const;
  Index nodeCount() const;
  /// Shortens a free polyline while keeping it free (same end points).
  std::vector<Eigen::Vector3d> tighten(std::vector<Eigen::Vector3d> points) const;
  void rasterise(const octomap::OcTree& map);
  void distanceTransform();

  OracleOptions options_;
  Eigen::Vector3d origin_;  ///< m, corner of cell (0, 0, 0)
  int size_[3] = {0, 0, 0};
  std::vector<float> distance_;  ///< m per cell (occupancy, then squared cells, then metres)
  Eigen::Vector3d min_corner_, max_corner_;
  int search_layers_ = 0;  ///< cells in z the search uses (1 in fixed-depth mode)
};

/// Length of a polyline (m).
double polylineLength(const std::vector<Eigen::Vector3d>& points);

}  // namespace auv::planning::bench
