// The ground-truth trajectory reader (TUM) and its interpolation.
#include <gtest/gtest.h>

#include <fstream>

#include "auv/sim/camera/trajectory.h"
#include "auv/sim/common/yaml_section.h"
#include "camera_test_scenes.h"

namespace auv::sim {
namespace {

std::string writeFile(const std::string& name, const std::string& text) {
  const std::string path = test::freshFolder("trajectory_" + name) + "/trajectory.tum";
  std::ofstream(path) << text;
  return path;
}

std::string loadError(const std::string& name, const std::string& text) {
  try {
    Trajectory::load(writeFile(name, text));
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "no error";
}

TEST(Trajectory, ReadsTumAndInterpolates) {
  const double s = std::sqrt(0.5);
  const std::string path = writeFile("ok",
                                     "# t x y z qx qy qz qw\n"
                                     "\n"
                                     "10.0 0 0 3 0 0 0 1\n"
                                     "12.0 2 4 5 0 0 " +
                                         std::to_string(s) + " " + std::to_string(s) + "\n");
  const Trajectory trajectory = Trajectory::load(path);
  ASSERT_EQ(trajectory.samples().size(), 2u);
  EXPECT_EQ(trajectory.startTime(), 10.0);
  EXPECT_EQ(trajectory.endTime(), 12.0);
  const Eigen::Isometry3d mid = trajectory.poseAt(11.0);
  EXPECT_TRUE(mid.translation().isApprox(Eigen::Vector3d(1, 2, 4), 1e-12));
  // Halfway between yaw 0 and yaw 90 deg: yaw 45 deg (slerp).
  const double yaw = std::atan2(mid.linear()(1, 0), mid.linear()(0, 0));
  EXPECT_NEAR(yaw, M_PI / 4, 1e-5);
  // Clamped outside the span.
  EXPECT_TRUE(trajectory.poseAt(0.0).translation().isApprox(Eigen::Vector3d(0, 0, 3)));
  EXPECT_TRUE(trajectory.poseAt(99.0).translation().isApprox(Eigen::Vector3d(2, 4, 5)));
}

TEST(Trajectory, MalformedLinesNameTheFileAndLine) {
  std::string m = loadError("short", "0 0 0 0 0 0 0 1\n1 0 0 0 0 0 1\n");
  EXPECT_NE(m.find("trajectory.tum:2:"), std::string::npos) << m;
  EXPECT_NE(m.find("expected 8 numbers"), std::string::npos) << m;
  m = loadError("word", "# header\n0 0 0 0 0 0 0 1\n1 0 zero 0 0 0 0 1\n");
  EXPECT_NE(m.find("trajectory.tum:3:"), std::string::npos) << m;
  EXPECT_NE(m.find("'zero'"), std::string::npos) << m;
  m = loadError("backwards", "1 0 0 0 0 0 0 1\n0.5 0 0 0 0 0 0 1\n");
  EXPECT_NE(m.find("trajectory.tum:2:"), std::string::npos) << m;
  EXPECT_NE(m.find("does not increase"), std::string::npos) << m;
  m = loadError("quaternion", "0 0 0 0 0 0 0 2\n");
  EXPECT_NE(m.find("trajectory.tum:1:"), std::string::npos) << m;
  EXPECT_NE(m.find("unit length"), std::string::npos) << m;
  m = loadError("nan", "0 0 0 nan 0 0 0 1\n");
  EXPECT_NE(m.find("trajectory.tum:1:"), std::string::npos) << m;
  m = loadError("empty", "# nothing\n");
  EXPECT_NE(m.find("no trajectory samples"), std::string::npos) << m;
  try {
    Trajectory::load("/nonexistent/trajectory.tum");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/trajectory.tum"), std::string::npos);
  }
}

}  // namespace
}  // namespace auv::sim
