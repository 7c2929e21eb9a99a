// measureGaps on synthetic maps: a true 0.1 m map with two 8 m blocks 2.9 m apart, and own
// 0.5 m maps holding the same faces quantised to their voxels, with a misplaced copy of a face,
// closed, or with one face never seen.
#include "map_gaps.h"

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

namespace auv::planning::bench {
namespace {

constexpr double kDepth = 4.0;

/// Occupies the column of voxels at (x, y) for every x in [x0, x1] (one voxel apart) over the
/// depths within a voxel of kDepth.
void face(octomap::OcTree& map, double y, double x0, double x1) {
  const double step = map.getResolution();
  for (double x = x0; x <= x1 + 1e-9; x += step) {
    for (double z = kDepth - step; z <= kDepth + step + 1e-9; z += step) {
      map.updateNode(octomap::point3d(x, y, z), true);
    }
  }
}

/// The truth: block A's faces at y -9.55 and -1.55, block B's at 1.45 and 9.45 (voxel
/// centres), x in [-6, 6]. The gap between the voxels' sides is 1.4 - (-1.5) = 2.9 m.
octomap::OcTree truth() {
  octomap::OcTree map(0.1);
  for (const double y : {-9.55, -1.55, 1.45, 9.45}) face(map, y, -5.95, 5.95);
  return map;
}

/// The gap's faces on a 0.5 m map: voxels [-2, -1.5) and [1, 1.5) in y: 2.5 m between them.
octomap::OcTree ownMap(bool with_b = true) {
  octomap::OcTree map(0.5);
  face(map, -1.75, -5.75, 5.75);
  if (with_b) face(map, 1.25, -5.75, 5.75);
  return map;
}

TEST(MapGaps, QuantisedFacesNarrowTheGap) {
  const auto gaps = measureGaps(truth(), ownMap(), kDepth);
  ASSERT_EQ(gaps.size(), 1u);  // the blocks' insides (8 m) are no gaps
  EXPECT_NEAR(gaps[0].centre, -0.05, 0.06);
  EXPECT_NEAR(gaps[0].true_width, 2.9, 0.06);
  ASSERT_TRUE(gaps[0].own_width.has_value());
  EXPECT_NEAR(*gaps[0].own_width, 2.5, 0.06);
}

TEST(MapGaps, AMisplacedCopyOfAFaceCountsWhereItIs) {
  octomap::OcTree own = ownMap();
  face(own, 0.75, 1.75, 2.25);  // voxels [0.5, 1) at x 1.75 and 2.25: the gap is 2 m there
  const auto gaps = measureGaps(truth(), own, kDepth);
  ASSERT_EQ(gaps.size(), 1u);
  ASSERT_TRUE(gaps[0].own_width.has_value());
  EXPECT_NEAR(*gaps[0].own_width, 2.0, 0.06);
}

TEST(MapGaps, AClosedGapIsZeroAndAnUnseenFaceIsNotMeasurable) {
  octomap::OcTree closed = ownMap();
  face(closed, -1.25, -0.25, 0.25);
  face(closed, -0.75, -0.25, 0.25);
  face(closed, -0.25, -0.25, 0.25);
  face(closed, 0.25, -0.25, 0.25);
  face(closed, 0.75, -0.25, 0.25);
  auto gaps = measureGaps(truth(), closed, kDepth);
  ASSERT_EQ(gaps.size(), 1u);
  ASSERT_TRUE(gaps[0].own_width.has_value());
  EXPECT_EQ(*gaps[0].own_width, 0.0);

  gaps = measureGaps(truth(), ownMap(false), kDepth);
  ASSERT_EQ(gaps.size(), 1u);
  EXPECT_FALSE(gaps[0].own_width.has_value());
}

}  // namespace
}  // namespace auv::planning::bench
