// Ray casting against analytic geometry: distances, normals, colours, closest points.
#include "auv/sim/raycast/ray_caster.h"

#include <gtest/gtest.h>

#include <random>

#include "test_meshes.h"

namespace auv::sim {
namespace {

TEST(RayCasterTest, DistanceToAWallMatchesTheAnalyticValueAtEveryAngle) {
  Mesh wall = test::wallAtX(5.0f, 50.0f);
  RayCaster caster(wall);
  for (double deg = -60; deg <= 60; deg += 7.5) {
    const float a = static_cast<float>(deg * M_PI / 180);
    const Eigen::Vector3f dir(std::cos(a), std::sin(a), 0);
    const RayHit hit = caster.cast(Eigen::Vector3f::Zero(), dir, 100.0f);
    ASSERT_TRUE(hit.hit()) << deg;
    EXPECT_NEAR(hit.distance, 5.0f / std::cos(a), 1e-4) << deg;
    EXPECT_NEAR(hit.normal.x(), -1.0f, 1e-5);  // faces the ray's origin
  }
}

TEST(RayCasterTest, MissesBeyondRangeAndBehind) {
  Mesh wall = test::wallAtX(5.0f, 50.0f);
  RayCaster caster(wall);
  EXPECT_FALSE(caster.cast({0, 0, 0}, {1, 0, 0}, 4.9f).hit());
  EXPECT_FALSE(caster.cast({0, 0, 0}, {-1, 0, 0}, 100.0f).hit());
  EXPECT_FALSE(caster.cast({0, 0, 0}, {0, 1, 0}, 100.0f).hit());
  EXPECT_TRUE(caster.occluded({0, 0, 0}, {1, 0, 0}, 6.0f));
  EXPECT_FALSE(caster.occluded({0, 0, 0}, {1, 0, 0}, 4.0f));
}

TEST(RayCasterTest, DistancesToASphereFromInsideAndOutside) {
  const Eigen::Vector3f center(10, -3, 4);
  const float radius = 2.0f;
  Mesh ball = test::sphere(center, radius);
  RayCaster caster(ball);
  std::mt19937 rng(7);
  std::normal_distribution<float> n(0, 1);
  // The tessellation is inside the true sphere by at most r(1 - cos(pi/rings)) ~ 2.4 mm.
  const float tolerance = radius * (1 - std::cos(static_cast<float>(M_PI) / 64)) + 1e-4f;
  std::vector<Eigen::Vector3f> origins, dirs;
  for (int i = 0; i < 500; ++i) {
    const Eigen::Vector3f d = Eigen::Vector3f(n(rng), n(rng), n(rng)).normalized();
    origins.push_back(center);
    dirs.push_back(d);
  }
  std::vector<RayHit> hits;
  caster.castMany(origins, dirs, 100.0f, hits);
  for (const RayHit& h : hits) {
    ASSERT_TRUE(h.hit());
    EXPECT_NEAR(h.distance, radius, tolerance);
  }
  // From outside, aimed at the centre: distance |o - c| - r, and the same as one by one.
  const Eigen::Vector3f origin(0, 0, 0);
  const Eigen::Vector3f dir = (center - origin).normalized();
  const RayHit single = caster.cast(origin, dir, 100.0f);
  ASSERT_TRUE(single.hit());
  EXPECT_NEAR(single.distance, (center - origin).norm() - radius, tolerance);
  EXPECT_NEAR(single.normal.dot(-dir), 1.0f, 1e-2);
}

TEST(RayCasterTest, BatchedAndSingleRaysAgree) {
  Mesh b = test::box({-1, -2, -3}, {4, 5, 6});
  RayCaster caster(b);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1, 1);
  std::vector<Eigen::Vector3f> origins, dirs;
  for (int i = 0; i < 1000; ++i) {
    origins.emplace_back(u(rng), u(rng), u(rng));
    dirs.push_back(Eigen::Vector3f(u(rng), u(rng), u(rng)).normalized());
  }
  std::vector<RayHit> hits;
  caster.castMany(origins, dirs, 100.0f, hits);
  for (size_t i = 0; i < hits.size(); ++i) {
    const RayHit one = caster.cast(origins[i], dirs[i], 100.0f);
    ASSERT_TRUE(hits[i].hit());
    EXPECT_EQ(hits[i].triangle, one.triangle);
    EXPECT_NEAR(hits[i].distance, one.distance, 1e-5);
    // The hit point lies on the box surface.
    const Eigen::Vector3f p = caster.pointAt(hits[i]);
    const Eigen::Vector3f q = origins[i] + hits[i].distance * dirs[i];
    EXPECT_LT((p - q).norm(), 1e-4);
  }
}

TEST(RayCasterTest, ClosestPointOnABox) {
  Mesh b = test::box({0, 0, 0}, {2, 2, 2});
  RayCaster caster(b);
  Eigen::Vector3f closest;
  uint32_t triangle = 0;
  ASSERT_TRUE(caster.closestPoint({3, 1, 1}, 5.0f, closest, triangle));
  EXPECT_LT((closest - Eigen::Vector3f(2, 1, 1)).norm(), 1e-5);
  ASSERT_TRUE(caster.closestPoint({3, 3, 1}, 5.0f, closest, triangle));  // nearest an edge
  EXPECT_LT((closest - Eigen::Vector3f(2, 2, 1)).norm(), 1e-5);
  ASSERT_TRUE(caster.closestPoint({1, 1, 0.5f}, 5.0f, closest, triangle));  // inside
  EXPECT_NEAR(closest.z(), 0.0f, 1e-5);
  EXPECT_FALSE(caster.closestPoint({10, 1, 1}, 2.0f, closest, triangle));  // out of reach
}

TEST(RayCasterTest, TextureLookupFollowsImageCoordinates) {
  // A quad at x = 1 facing -x; texture: left half red, right half blue, top row green.
  Mesh m;
  m.vertices = {{1, -1, -1}, {1, 1, -1}, {1, 1, 1}, {1, -1, 1}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  // u along +y, v along +z (image rows go down = +z in NED).
  m.triangle_uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 0}, {1, 1}, {0, 1}};
  m.texture = cv::Mat(64, 64, CV_8UC3, cv::Scalar(0, 0, 0));
  m.texture(cv::Rect(0, 0, 32, 64)).setTo(cv::Scalar(0, 0, 255));   // left: red
  m.texture(cv::Rect(32, 0, 32, 64)).setTo(cv::Scalar(255, 0, 0));  // right: blue
  m.texture(cv::Rect(0, 0, 64, 8)).setTo(cv::Scalar(0, 255, 0));    // top: green
  RayCaster caster(m);
  const auto colorAt = [&](float y, float z) {
    return caster.colorAt(caster.cast({0, y, z}, {1, 0, 0}, 10.0f));
  };
  EXPECT_GT(colorAt(-0.5f, 0.0f).x(), 0.9f);   // u = 0.25: red
  EXPECT_GT(colorAt(0.5f, 0.0f).z(), 0.9f);    // u = 0.75: blue
  EXPECT_GT(colorAt(0.0f, -0.95f).y(), 0.9f);  // v ~ 0: the image's top row
  EXPECT_NEAR(colorAt(-0.5f, 0.0f).y(), 0.0f, 1e-6);
}

TEST(RayCasterTest, VertexColoursAreInterpolatedInLinearLight) {
  Mesh wall = test::wallAtX(2.0f, 1.0f, {0.5f, 0.5f, 0.5f});
  RayCaster caster(wall);
  const Eigen::Vector3f c = caster.colorAt(caster.cast({0, 0, 0}, {1, 0, 0}, 10.0f));
  EXPECT_NEAR(c.x(), srgbToLinear(0.5f), 1e-5);  // 0.214
  EXPECT_NEAR(linearToSrgb(srgbToLinear(0.3f)), 0.3f, 1e-5);
}

}  // namespace
}  // namespace auv::sim
