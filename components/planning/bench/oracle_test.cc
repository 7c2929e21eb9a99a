// The shortest-path oracle against paths known in closed form: around the end of a wall with a
// gap (fixed depth and 3-D), over the top of a wall (3-D), a clear straight line, a closed wall.
#include "oracle.h"

#include <cmath>

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

namespace auv::planning::bench {
namespace {

constexpr double kResolution = 0.1;
constexpr double kClearance = 0.65;

/// A 0.1 m map whose known box is x [-10, 10], y [-6, 6], z [0, 4] (two free corner voxels;
/// everything else unknown, which the oracle treats as free).
std::unique_ptr<octomap::OcTree> emptyBoxMap() {
  auto tree = std::make_unique<octomap::OcTree>(kResolution);
  const float free = tree->getClampingThresMinLog();
  tree->setNodeValue(octomap::point3d(-9.95f, -5.95f, 0.05f), free);
  tree->setNodeValue(octomap::point3d(9.95f, 5.95f, 3.95f), free);
  return tree;
}

/// Occupies every voxel whose centre lies in [min, max].
void occupy(octomap::OcTree& tree, const Eigen::Vector3d& min, const Eigen::Vector3d& max) {
  const float occupied = tree.getClampingThresMaxLog();
  for (double x = min.x(); x <= max.x() + 1e-9; x += kResolution) {
    for (double y = min.y(); y <= max.y() + 1e-9; y += kResolution) {
      for (double z = min.z(); z <= max.z() + 1e-9; z += kResolution) {
        tree.setNodeValue(octomap::point3d(x, y, z), occupied);
      }
    }
  }
}

/// Shortest path from p to g around a disc of radius r at c when the straight line is blocked
/// on the side the short angle between c->p and c->g sweeps: tangent, arc, tangent.
double wrapAroundLength(const Eigen::Vector2d& p, const Eigen::Vector2d& g,
                        const Eigen::Vector2d& c, double r) {
  const Eigen::Vector2d to_p = p - c, to_g = g - c;
  const double short_angle = std::acos(to_p.dot(to_g) / (to_p.norm() * to_g.norm()));
  const double tangent_p = std::sqrt(to_p.squaredNorm() - r * r);
  const double tangent_g = std::sqrt(to_g.squaredNorm() - r * r);
  const double arc =
      2.0 * M_PI - short_angle - std::acos(r / to_p.norm()) - std::acos(r / to_g.norm());
  return tangent_p + tangent_g + r * arc;
}

/// Wall in the plane y = 0.05 (one voxel thick, full depth) with a gap for x in [4, 8).
std::unique_ptr<octomap::OcTree> wallWithGap() {
  auto tree = emptyBoxMap();
  occupy(*tree, {-9.95, 0.05, 0.05}, {3.95, 0.05, 3.95});
  occupy(*tree, {8.05, 0.05, 0.05}, {9.95, 0.05, 3.95});
  return tree;
}

void expectFree(const ShortestPathOracle& oracle, const OraclePath& path) {
  for (std::size_t i = 1; i < path.points.size(); ++i) {
    EXPECT_TRUE(oracle.lineOfSight(path.points[i - 1], path.points[i])) << "segment " << i;
  }
}

// A vehicle's own map ends where its sonar saw: a start outside the known box is an error,
// and with padding the box grows as free space (straight line, exact length).
TEST(ShortestPathOracle, PaddingGrowsTheSearchableBoxAsFreeSpace) {
  const auto map = wallWithGap();
  OracleOptions options;
  options.clearance = kClearance;
  options.grid = 0.1;
  options.fixed_depth = 2.05;
  const Eigen::Vector3d start(-9.0, -8.0, 2.05), goal(-9.0, -2.0, 2.05);  // y -8: outside
  EXPECT_THROW(ShortestPathOracle(*map, options).shortestPath(start, goal), OracleError);
  options.padding = 3.0;
  const ShortestPathOracle padded(*map, options);
  EXPECT_LE(padded.minCorner().y(), -8.95 + 1e-9);
  const OraclePath path = padded.shortestPath(start, goal);
  ASSERT_TRUE(path.found);
  EXPECT_NEAR(path.length, 6.0, 1e-9);
  options.padding = -1.0;
  EXPECT_THROW(ShortestPathOracle(*map, options), OracleError);
}

// The gap of wallWithGap() is 4.1 m between voxel centres (x 3.95 and 8.05): joined up to a
// clearance of half that, less the search grid's quantisation (its nodes are cell centres,
// x 5.95 or 6.05 in the gap: 2.0 m from a wall end).
TEST(ShortestPathOracle, BottleneckClearanceIsHalfTheGap) {
  const auto map = wallWithGap();
  OracleOptions options;
  options.clearance = 3.0;  // the upper end of the search
  options.grid = 0.1;
  options.fixed_depth = 2.05;
  ShortestPathOracle oracle(*map, options);
  const Eigen::Vector3d south(6.0, -5.0, 2.05), north(6.0, 5.0, 2.05);
  EXPECT_NEAR(oracle.bottleneckClearance(south, north), 2.0, 0.02);
  EXPECT_EQ(oracle.options().clearance, 3.0);  // restored
  // Both ends 5 m south of the wall, 2 m apart in open water: only the search's top limits.
  EXPECT_NEAR(oracle.bottleneckClearance({-8.0, -5.0, 2.05}, {-6.0, -5.0, 2.05}), 3.0, 1e-9);
  // An end inside the wall: not joined at any clearance.
  EXPECT_EQ(oracle.bottleneckClearance({0.0, 0.05, 2.05}, north), 0.0);
  EXPECT_THROW(oracle.bottleneckClearance(south, north, 0.0), OracleError);
}

TEST(ShortestPathOracle, GoesRoundTheWallEndAtFixedDepth) {
  const auto map = wallWithGap();
  OracleOptions options;
  options.clearance = kClearance;
  options.grid = 0.1;
  options.fixed_depth = 2.05;  // a voxel-centre layer: the wall end is a point in the plane
  const ShortestPathOracle oracle(*map, options);
  const Eigen::Vector3d start(0.0, -5.0, 2.05), goal(0.0, 5.0, 2.05);
  const OraclePath path = oracle.shortestPath(start, goal);
  ASSERT_TRUE(path.found);
  // The nearest wall voxel centre to the gap is (3.95, 0.05): the path bends round it.
  const double expected = wrapAroundLength({0.0, -5.0}, {0.0, 5.0}, {3.95, 0.05}, kClearance);
  EXPECT_NEAR(path.length, expected, 0.003 * expected);
  EXPECT_GT(path.length, 10.0);
  EXPECT_EQ(path.points.front(), start);
  EXPECT_EQ(path.points.back(), goal);
  expectFree(oracle, path);
}

TEST(ShortestPathOracle, StaysCloseOnAGridCoarserThanTheMap) {
  // 0.2 m cells hold the 0.1 m voxels: the wall end moves by up to half a cell.
  const auto map = wallWithGap();
  OracleOptions options;
  options.clearance = kClearance;
  options.grid = 0.2;
  options.fixed_depth = 2.05;
  const ShortestPathOracle oracle(*map, options);
  const OraclePath path = oracle.shortestPath({0.0, -5.0, 2.05}, {0.0, 5.0, 2.05});
  ASSERT_TRUE(path.found);
  const double expected = wrapAroundLength({0.0, -5.0}, {0.0, 5.0}, {3.95, 0.05}, kClearance);
  EXPECT_NEAR(path.length, expected, 0.01 * expected);
  expectFree(oracle, path);
}

TEST(ShortestPathOracle, GoesRoundTheWallEndIn3d) {
  const auto map = wallWithGap();
  OracleOptions options;
  options.clearance = kClearance;
  options.grid = 0.1;
  const ShortestPathOracle oracle(*map, options);
  const OraclePath path = oracle.shortestPath({0.0, -5.0, 2.05}, {0.0, 5.0, 2.05});
  ASSERT_TRUE(path.found);
  const double expected = wrapAroundLength({0.0, -5.0}, {0.0, 5.0}, {3.95, 0.05}, kClearance);
  EXPECT_NEAR(path.length, expected, 0.003 * expected);
  expectFree(oracle, path);
}

TEST(ShortestPathOracle, GoesOverTheTopOfAWallIn3d) {
  // A wall across the whole box from 1.5 m depth down: the way is over its top edge, whose
  // nearest voxel centres are at (y, z) = (0.05, 1.55).
  auto map = emptyBoxMap();
  occupy(*map, {-9.95, 0.05, 1.55}, {9.95, 0.05, 3.95});
  OracleOptions options;
  options.clearance = kClearance;
  options.grid = 0.1;
  const ShortestPathOracle oracle(*map, options);
  const OraclePath path = oracle.shortestPath({1.05, -3.0, 3.05}, {1.05, 3.0, 3.05});
  ASSERT_TRUE(path.found);
  const double expected = wrapAroundLength({-3.0, 3.05}, {3.0, 3.05}, {0.05, 1.55}, kClearance);
  EXPECT_NEAR(path.length, expected, 0.003 * expected);
  expectFree(oracle, path);
  // The same wall at fixed depth: no way round.
  options.fixed_depth = 3.05;
  const ShortestPathOracle plane(*map, options);
  EXPECT_FALSE(plane.shortestPath({1.05, -3.0, 3.05}, {1.05, 3.0, 3.05}).found);
}

TEST(ShortestPathOracle, DepthBandKeepsThePathBetweenMinAndMaxDepth) {
  // A wall across the whole box from the surface down to 2.45 m: the way is under its bottom
  // edge, at 2.45 + 0.65 = 3.1 m or deeper.
  auto map = emptyBoxMap();
  occupy(*map, {-9.95, 0.05, 0.05}, {9.95, 0.05, 2.45});
  OracleOptions options;
  options.clearance = kClearance;
  options.grid = 0.1;
  options.max_depth = 3.5;
  const ShortestPathOracle deep(*map, options);
  const OraclePath path = deep.shortestPath({1.05, -3.0, 2.05}, {1.05, 3.0, 2.05});
  ASSERT_TRUE(path.found);
  for (const Eigen::Vector3d& point : path.points) EXPECT_LE(point.z(), 3.5 + 1e-9);
  expectFree(deep, path);
  options.max_depth = 3.0;  // above the way under the wall
  const ShortestPathOracle shallow(*map, options);
  EXPECT_FALSE(shallow.shortestPath({1.05, -3.0, 2.05}, {1.05, 3.0, 2.05}).found);
  options.min_depth = 3.0;  // the band is empty
  EXPECT_THROW(ShortestPathOracle(*map, options), OracleError);
}

TEST(ShortestPathOracle, StraightLineWhenNothingIsInTheWay) {
  const auto map = wallWithGap();
  OracleOptions options;
  options.clearance = kClearance;
  options.grid = 0.2;
  options.fixed_depth = 2.0;
  const ShortestPathOracle oracle(*map, options);
  const OraclePath path = oracle.shortestPath({-8.0, -4.0, 2.0}, {7.0, -1.0, 2.0});
  ASSERT_TRUE(path.found);
  EXPECT_DOUBLE_EQ(path.length, std::hypot(15.0, 3.0));
  EXPECT_EQ(path.points.size(), 2u);
}

TEST(ShortestPathOracle, ReportsNoPathThroughAClosedWallOrANarrowGap) {
  auto map = emptyBoxMap();
  occupy(*map, {-9.95, 0.05, 0.05}, {3.95, 0.05, 3.95});
  occupy(*map, {5.05, 0.05, 0.05}, {9.95, 0.05, 3.95});  // a 1.1 m gap < 2 x 0.65 m
  OracleOptions options;
  options.clearance = kClearance;
  options.grid = 0.1;
  options.fixed_depth = 2.05;
  const ShortestPathOracle oracle(*map, options);
  EXPECT_FALSE(oracle.shortestPath({0.0, -5.0, 2.05}, {0.0, 5.0, 2.05}).found);
  options.clearance = 0.4;  // 2 x 0.4 m fits
  const ShortestPathOracle thinner(*map, options);
  EXPECT_TRUE(thinner.shortestPath({0.0, -5.0, 2.05}, {0.0, 5.0, 2.05}).found);
}

TEST(ShortestPathOracle, RejectsAStartTooCloseToTheMapOrOutsideIt) {
  const auto map = wallWithGap();
  OracleOptions options;
  options.clearance = kClearance;
  options.fixed_depth = 2.0;
  const ShortestPathOracle oracle(*map, options);
  EXPECT_THROW(oracle.shortestPath({0.0, 0.3, 2.0}, {0.0, 5.0, 2.0}), OracleError);
  EXPECT_THROW(oracle.shortestPath({0.0, -5.0, 2.0}, {30.0, 5.0, 2.0}), OracleError);
  options.grid = -1.0;
  EXPECT_THROW((ShortestPathOracle{*map, options}), OracleError);
}

TEST(ShortestPathOracle, DistanceIsExactAtCellCentres) {
  const auto map = wallWithGap();
  OracleOptions options;
  options.grid = 0.1;
  const ShortestPathOracle oracle(*map, options);
  EXPECT_NEAR(oracle.distance({3.95, 1.05, 2.05}), 1.0, 1e-6);
  EXPECT_NEAR(oracle.distance({5.95, 0.05, 2.05}), 2.0, 1e-6);  // the wall end at 3.95
  EXPECT_NEAR(oracle.distance({4.95, -0.95, 2.05}), std::sqrt(2.0), 1e-5);
}

}  // namespace
}  // namespace auv::planning::bench
