// Precision, recall and F-score (Tanks and Temples) on synthetic surfaces with known distances;
// surface sampling; the well-imaged region of a scene with an occluder.
#include "auv/recon/evaluate/surface_metrics.h"

#include <gtest/gtest.h>

#include <cmath>

#include "auv/recon/common/stage_error.h"
#include "auv/recon/evaluate/well_imaged_region.h"
#include "synthetic_scene.h"

namespace auv::recon::evaluate {
namespace {

using testing::planeMesh;

TEST(ScoreDistances, DefinitionOnKnownDistances) {
  // Precision: 3 of 4 points within 5 cm; recall: 1 of 2 samples within 5 cm.
  const SurfaceScores s = scoreDistances({0.01, 0.02, 0.04, 0.3}, {0.0, 0.5}, {0.05, 1.0});
  ASSERT_EQ(s.scores.size(), 2u);
  EXPECT_DOUBLE_EQ(s.scores[0].precision, 0.75);
  EXPECT_DOUBLE_EQ(s.scores[0].recall, 0.5);
  EXPECT_DOUBLE_EQ(s.scores[0].fscore, 2 * 0.75 * 0.5 / 1.25);
  EXPECT_DOUBLE_EQ(s.scores[1].fscore, 1.0);
  EXPECT_DOUBLE_EQ(s.mean_accuracy_m, (0.01 + 0.02 + 0.04 + 0.3) / 4);
  EXPECT_DOUBLE_EQ(s.median_accuracy_m, 0.03);
  EXPECT_DOUBLE_EQ(s.median_completeness_m, 0.25);
  // Nothing reconstructed: F = 0, not NaN.
  const SurfaceScores empty = scoreDistances({}, {0.1}, {0.05});
  EXPECT_EQ(empty.scores[0].fscore, 0.0);
}

// Poisson meshes hold a few zero-area triangles; Open3D 0.16's closest-point query aborted the
// process on them (an internal assertion) when the canyon survey's mesh was evaluated.
TEST(DistancesToMesh, ExactAndUnharmedByDegenerateTriangles) {
  open3d::geometry::TriangleMesh mesh;
  mesh.vertices_ = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}, {3, 0, 0}, {4, 0, 0}};
  mesh.triangles_ = {{0, 1, 2}, {3, 4, 5}, {1, 1, 2}, {0, 0, 0}};  // collinear, repeated corners
  const std::vector<double> d =
      distancesToMesh({{0.2, 0.2, 0.5}, {0.2, 0.2, -2.0}, {3, 0, 1}}, mesh);
  ASSERT_EQ(d.size(), 3u);
  EXPECT_NEAR(d[0], 0.5, 1e-6);
  EXPECT_NEAR(d[1], 2.0, 1e-6);
  // (3, 0, 1) lies 1 m above the collinear triangle's segment: left out, the nearest surface
  // is the corner (1, 0, 0) of the real triangle.
  EXPECT_NEAR(d[2], std::sqrt(5.0), 1e-6);
  mesh.triangles_ = {{1, 1, 2}};  // nothing but degenerate triangles: no surface
  EXPECT_TRUE(std::isinf(distancesToMesh({{0, 0, 0}}, mesh)[0]));
}

TEST(SampleSurface, DensityDeterminismAndPlacement) {
  const auto plane = planeMesh(5.0, 2.0, 4);  // 4 m^2
  const SurfaceSamples a = sampleSurface(plane, 0.02, 7);
  EXPECT_NEAR(static_cast<double>(a.size()), 4.0 / (0.02 * 0.02), 4.0 / (0.02 * 0.02) * 0.02);
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_NEAR(a.points[i].z(), 5.0, 1e-12);
    EXPECT_LE(std::abs(a.points[i].x()), 1.0 + 1e-12);
    EXPECT_NEAR(std::abs(a.normals[i].z()), 1.0, 1e-12);
  }
  const SurfaceSamples b = sampleSurface(plane, 0.02, 7);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(a.points.front(), b.points.front());
  EXPECT_EQ(a.points.back(), b.points.back());
  // A subset of triangles gives exactly those triangles' samples.
  const std::vector<size_t> first{0};
  const SurfaceSamples one = sampleSurface(plane, 0.02, 7, &first);
  ASSERT_FALSE(one.points.empty());
  EXPECT_EQ(one.points.front(), a.points.front());
}

class FScoreOnAPlane : public ::testing::Test {
 protected:
  // Truth: a 4 m x 4 m plane at depth 5; all of it counts as well imaged.
  open3d::geometry::TriangleMesh truth_ = planeMesh(5.0, 4.0, 8);
  SurfaceSamples samples_ = sampleSurface(truth_, 0.02, 1);
  std::vector<bool> region_ = std::vector<bool>(samples_.size(), true);
  std::vector<double> thresholds_{0.02, 0.05, 0.10};
};

TEST_F(FScoreOnAPlane, PerfectReconstructionScoresOne) {
  // A reconstruction denser than the truth samples, on the surface.
  const SurfaceSamples rec = sampleSurface(truth_, 0.01, 99);
  const SurfaceScores s =
      scoreSurface(truth_, samples_.points, region_, rec.points, nullptr, thresholds_);
  for (const ThresholdScore& t : s.scores) {
    EXPECT_DOUBLE_EQ(t.precision, 1.0) << t.threshold_m;
    EXPECT_GT(t.recall, 0.999) << t.threshold_m;  // 1 cm spacing: every sample within 2 cm
    EXPECT_GT(t.fscore, 0.999) << t.threshold_m;
  }
  EXPECT_LT(s.mean_accuracy_m, 1e-5);
  // The truth mesh itself as the reconstruction (recall to its triangles): exactly 1.
  const SurfaceScores m =
      scoreSurface(truth_, samples_.points, region_, rec.points, &truth_, thresholds_);
  EXPECT_DOUBLE_EQ(m.scores[0].recall, 1.0);
}

TEST_F(FScoreOnAPlane, ShiftedReconstructionDropsBelowTheShift) {
  // The same plane 3 cm too deep: nothing within 2 cm, everything within 5 cm.
  SurfaceSamples rec = sampleSurface(truth_, 0.01, 99);
  for (auto& p : rec.points) p.z() += 0.03;
  const SurfaceScores s =
      scoreSurface(truth_, samples_.points, region_, rec.points, nullptr, thresholds_);
  EXPECT_DOUBLE_EQ(s.scores[0].precision, 0.0);
  EXPECT_LT(s.scores[0].recall, 0.001);
  EXPECT_LT(s.scores[0].fscore, 0.001);
  EXPECT_DOUBLE_EQ(s.scores[1].precision, 1.0);
  EXPECT_GT(s.scores[1].recall, 0.999);
  EXPECT_NEAR(s.median_accuracy_m, 0.03, 1e-5);
  // Half of it missing: recall halves, precision stays.
  std::vector<Eigen::Vector3d> half;
  for (const auto& p : rec.points) {
    if (p.x() < 0) half.push_back(p);
  }
  const SurfaceScores h =
      scoreSurface(truth_, samples_.points, region_, half, nullptr, thresholds_);
  EXPECT_DOUBLE_EQ(h.scores[1].precision, 1.0);
  EXPECT_NEAR(h.scores[1].recall, 0.5, 0.02);
  EXPECT_NEAR(h.scores[1].fscore, 2 * 0.5 / 1.5, 0.02);
}

TEST_F(FScoreOnAPlane, OnlyTheRegionCounts) {
  // Region = the x < 0 half; a reconstruction of the x >= 0 half only, plus a 1 m outlier
  // above the region: precision is over the outlier alone, recall is 0.
  std::vector<bool> region(samples_.size());
  for (size_t i = 0; i < samples_.size(); ++i) region[i] = samples_.points[i].x() < 0;
  std::vector<Eigen::Vector3d> rec;
  for (const auto& p : sampleSurface(truth_, 0.01, 3).points) {
    if (p.x() >= 0.1) rec.push_back(p);
  }
  rec.emplace_back(-1.0, 0.0, 4.0);
  const SurfaceScores s = scoreSurface(truth_, samples_.points, region, rec, nullptr, thresholds_);
  EXPECT_EQ(s.points_evaluated, 1u);
  EXPECT_EQ(s.points_outside, rec.size() - 1);
  EXPECT_DOUBLE_EQ(s.scores[2].precision, 0.0);
  EXPECT_DOUBLE_EQ(s.scores[2].recall, 0.0);
  EXPECT_NEAR(s.mean_accuracy_m, 1.0, 1e-6);
}

TEST(WellImagedRegion, ViewsRangeIncidenceAndOcclusion) {
  // Seabed at depth 5; two down cameras at depth 3 (2 m above), 1 m apart along x; a third
  // camera far away (beyond range); an opaque slab at depth 4 over x in [-3, -2].
  open3d::geometry::TriangleMesh world = planeMesh(5.0, 10.0, 20);
  const open3d::geometry::TriangleMesh slab = planeMesh(4.0, 1.0, 1, -2.5, 0.0);
  world += slab;
  const scene::Camera lens = scene::Camera::pinhole(1, 400, 300, 200, 200, 199.5, 149.5);
  std::vector<View> views;
  for (const Eigen::Vector3d& c :
       {Eigen::Vector3d(0, 0, 3), Eigen::Vector3d(1, 0, 3), Eigen::Vector3d(-2.5, 0, 3),
        Eigen::Vector3d(-2.5, 0.2, 3), Eigen::Vector3d(40, 0, 3)}) {
    const scene::Image image = testing::downCamera(1, 1, c, "x");
    views.push_back(View{lens, image.rotation(), image.t_cw});
  }
  SurfaceSamples samples;
  const Eigen::Vector3d up(0, 0, -1);
  auto add = [&](const Eigen::Vector3d& p) {
    samples.points.push_back(p);
    samples.normals.push_back(up);
  };
  add({0.5, 0, 5});   // 0: below both first cameras -> 2 views
  add({-0.7, 0, 5});  // 1: in view of camera 0 only (camera 1's image spans x in [-0.5, 2.5])
  add({-2.5, 0, 5});  // 2: under the slab: the cameras above it see the slab instead
  add({-2.5, 0, 4});  // 3: on the slab: seen by cameras 2 and 3
  add({40, 0, 5});    // 4: below the far camera only
  add({4.0, 0, 5});   // 5: outside every image
  const OcclusionTester occlusion(world);
  WellImagedOptions options;
  options.max_range_m = 4.5;
  options.min_views = 2;
  std::vector<uint8_t> counts = countViews(samples, views, occlusion, options);
  EXPECT_EQ(counts[0], 2);
  EXPECT_EQ(counts[1], 1);
  EXPECT_EQ(counts[2], 0);
  EXPECT_EQ(counts[3], 2);
  EXPECT_EQ(counts[4], 1);
  EXPECT_EQ(counts[5], 0);
  // Out of range: 2 m is beyond 1.5 m.
  options.max_range_m = 1.5;
  counts = countViews(samples, views, occlusion, options);
  EXPECT_EQ(counts[0], 0);
  EXPECT_EQ(counts[3], 2);  // 1 m below its cameras
  // Oblique views: with a normal along x, both first cameras see the point 76 deg off it.
  SurfaceSamples tilted;
  tilted.points.push_back({0.5, 0, 5});
  tilted.normals.push_back({1, 0, 0});
  options.max_range_m = 4.5;
  EXPECT_EQ(countViews(tilted, views, occlusion, options)[0], 2);  // 80 deg allowed
  options.max_incidence_deg = 70;
  EXPECT_EQ(countViews(tilted, views, occlusion, options)[0], 0);
  // Bad options name the field.
  options.min_views = 0;
  EXPECT_THROW(countViews(samples, views, occlusion, options), OptionError);
}

TEST(WellImagedRegion, TrianglesNearTheCameras) {
  const auto plane = planeMesh(5.0, 10.0, 10);  // 1 m cells
  const std::vector<size_t> near = trianglesNear(plane, {Eigen::Vector3d(0, 0, 3)}, 2.5);
  // Within 2.5 m of a point 2 m above the centre: a disc of radius 1.5 m (plus a cell).
  EXPECT_GT(near.size(), 8u);
  EXPECT_LT(near.size(), 60u);
  EXPECT_TRUE(trianglesNear(plane, {}, 2.5).empty());
}

TEST(OcclusionTester, SegmentsAgainstAPlane) {
  const auto plane = planeMesh(5.0, 2.0, 2);
  const OcclusionTester tester(plane);
  EXPECT_TRUE(tester.visible({0, 0, 3}, {0, 0, 5}, 0.01));   // ends on the plane
  EXPECT_FALSE(tester.visible({0, 0, 3}, {0, 0, 6}, 0.01));  // crosses it
  EXPECT_TRUE(tester.visible({0, 0, 3}, {3, 0, 6}, 0.01));   // passes beside it
}

}  // namespace
}  // namespace auv::recon::evaluate
