// Hull (capsule) contacts against a wall and the seabed: the ground truth of safety checks.
#include "auv/sim/world/hull_contact.h"

#include <gtest/gtest.h>

#include "test_meshes.h"

namespace auv::sim {
namespace {

Eigen::Isometry3d poseAt(double x, double y, double z, double yaw) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

TEST(HullContactTest, NoseIntoAWallTouchesExactlyWhenTheTipReachesIt) {
  Mesh wall = test::wallAtX(10.0f, 20.0f);
  RayCaster world(wall);
  const HullShape hull;  // 1.6 m long: tip 0.8 m ahead of the centre
  EXPECT_FALSE(findHullContact(world, 100, hull, poseAt(9.15, 0, 5, 0)));
  const auto contact = findHullContact(world, 100, hull, poseAt(9.25, 0, 5, 0));
  ASSERT_TRUE(contact);
  EXPECT_NEAR(contact->penetration, 0.05, 1e-3);
  EXPECT_NEAR(contact->point.x(), 10.0, 1e-4);
  EXPECT_NEAR(contact->normal.x(), -1.0, 1e-3);  // pushes the hull back from the wall
}

TEST(HullContactTest, BroadsideToAWallTouchesAtTheHullRadius) {
  Mesh wall = test::wallAtX(10.0f, 20.0f);
  RayCaster world(wall);
  const HullShape hull;
  // Heading east (yaw pi/2): the hull's side faces the wall at x = 10.
  EXPECT_FALSE(findHullContact(world, 100, hull, poseAt(10.0 - 0.13, 0, 5, M_PI / 2)));
  const auto contact = findHullContact(world, 100, hull, poseAt(10.0 - 0.10, 0, 5, M_PI / 2));
  ASSERT_TRUE(contact);
  EXPECT_NEAR(contact->penetration, 0.015, 1e-3);
}

TEST(HullContactTest, TheFlatSeabedCounts) {
  Mesh wall = test::wallAtX(100.0f, 1.0f);
  RayCaster world(wall);
  const HullShape hull;
  EXPECT_FALSE(findHullContact(world, 10.0, hull, poseAt(0, 0, 9.8, 0)));
  const auto contact = findHullContact(world, 10.0, hull, poseAt(0, 0, 9.95, 0));
  ASSERT_TRUE(contact);
  EXPECT_EQ(contact->triangle, RayHit::kNoHit);
  EXPECT_NEAR(contact->penetration, 0.065, 1e-6);
}

}  // namespace
}  // namespace auv::sim
