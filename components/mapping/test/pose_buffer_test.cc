// PoseBuffer: interpolation against analytic poses, bounds and out-of-order input.
#include "auv/mapping/pose_buffer.h"

#include <gtest/gtest.h>

#include <cmath>

namespace auv::mapping {
namespace {

constexpr int64_t kSecond = 1000000000;

StampedPose poseAt(int64_t stamp_ns, Eigen::Vector3d position, double yaw) {
  StampedPose pose;
  pose.stamp_ns = stamp_ns;
  pose.position = position;
  pose.orientation = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ());
  return pose;
}

TEST(PoseBufferTest, InterpolatesPositionLinearlyAndYawBySlerp) {
  PoseBuffer buffer;
  buffer.add(poseAt(10 * kSecond, {0, 0, 2}, 0.0));
  buffer.add(poseAt(10 * kSecond + kSecond / 5, {1, 2, 4}, 0.4));
  PoseLookupStatus status;
  const auto pose = buffer.lookUp(10 * kSecond + kSecond / 20, &status);  // 1/4 of the way
  ASSERT_TRUE(pose) << toString(status);
  EXPECT_EQ(status, PoseLookupStatus::OK);
  EXPECT_NEAR(pose->position.x(), 0.25, 1e-12);
  EXPECT_NEAR(pose->position.y(), 0.5, 1e-12);
  EXPECT_NEAR(pose->position.z(), 2.5, 1e-12);
  const Eigen::AngleAxisd rotation(pose->orientation);
  EXPECT_NEAR(rotation.angle(), 0.1, 1e-9);
  EXPECT_NEAR(std::abs(rotation.axis().z()), 1.0, 1e-9);
}

TEST(PoseBufferTest, SlerpTakesTheShortArcAcrossPi) {
  PoseBuffer buffer;
  buffer.add(poseAt(0, {0, 0, 0}, M_PI - 0.1));
  buffer.add(poseAt(kSecond / 10, {0, 0, 0}, -M_PI + 0.1));  // 0.2 rad further, across +-pi
  const auto pose = buffer.lookUp(kSecond / 20);
  ASSERT_TRUE(pose);
  const Eigen::Vector3d heading = pose->orientation * Eigen::Vector3d::UnitX();
  // Half-way along the short arc is heading pi (the long arc would give heading 0).
  EXPECT_NEAR(heading.x(), -1.0, 1e-9) << heading.transpose();
  EXPECT_NEAR(heading.y(), 0.0, 1e-9) << heading.transpose();
}

TEST(PoseBufferTest, ReportsStampsOutsideTheBuffer) {
  PoseBuffer::Options options;
  options.capacity = 3;
  PoseBuffer buffer(options);
  PoseLookupStatus status;
  EXPECT_FALSE(buffer.lookUp(0, &status));
  EXPECT_EQ(status, PoseLookupStatus::EMPTY);
  for (int i = 0; i < 5; ++i) buffer.add(poseAt(i * kSecond / 10, {double(i), 0, 0}, 0));
  EXPECT_EQ(buffer.size(), 3u);  // bounded: the two oldest were dropped
  EXPECT_FALSE(buffer.lookUp(kSecond / 10, &status));
  EXPECT_EQ(status, PoseLookupStatus::BEFORE_START);
  EXPECT_FALSE(buffer.lookUp(kSecond, &status));
  EXPECT_EQ(status, PoseLookupStatus::AFTER_END);
  const auto last = buffer.lookUp(4 * kSecond / 10, &status);
  ASSERT_TRUE(last);
  EXPECT_DOUBLE_EQ(last->position.x(), 4.0);
}

TEST(PoseBufferTest, RefusesToBridgeLongGaps) {
  PoseBuffer::Options options;
  options.max_gap_s = 0.5;
  PoseBuffer buffer(options);
  buffer.add(poseAt(0, {0, 0, 0}, 0));
  buffer.add(poseAt(kSecond, {10, 0, 0}, 0));
  PoseLookupStatus status;
  EXPECT_FALSE(buffer.lookUp(kSecond / 2, &status));
  EXPECT_EQ(status, PoseLookupStatus::GAP_TOO_LONG);
}

TEST(PoseBufferTest, SortsOutOfOrderPosesAndHoldsWithinExtrapolation) {
  PoseBuffer::Options options;
  options.max_extrapolation_s = 0.1;
  PoseBuffer buffer(options);
  buffer.add(poseAt(2 * kSecond / 10, {2, 0, 0}, 0));
  buffer.add(poseAt(0, {0, 0, 0}, 0));
  buffer.add(poseAt(kSecond / 10, {1, 0, 0}, 0));
  EXPECT_EQ(buffer.oldestStampNs(), 0);
  const auto mid = buffer.lookUp(kSecond * 15 / 100);
  ASSERT_TRUE(mid);
  EXPECT_NEAR(mid->position.x(), 1.5, 1e-12);
  const auto held = buffer.lookUp(kSecond * 25 / 100);
  ASSERT_TRUE(held);
  EXPECT_DOUBLE_EQ(held->position.x(), 2.0);
}

TEST(PoseBufferTest, RejectsBadOptions) {
  PoseBuffer::Options options;
  options.capacity = 1;
  EXPECT_THROW(PoseBuffer{options}, std::invalid_argument);
}

}  // namespace
}  // namespace auv::mapping
