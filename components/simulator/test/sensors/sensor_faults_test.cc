// The fault campaign's sensor faults: windows of silence and navigation jumps, parsed from the
// simulator's `faults` parameter; bad entries are refused naming the entry.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "auv/sim/sensors/sensor_faults.h"

namespace auv::sim {
namespace {

TEST(SensorFaultsTest, WindowsCoverTheirTimeOnly) {
  const SensorFaults faults =
      SensorFaults::parse({"sonar_silent@120+30", "dvl_lost@10.5+2", "navigation_silent@0+1"});
  EXPECT_FALSE(faults.active(SensorFaultKind::SONAR_SILENT, 119.9));
  EXPECT_TRUE(faults.active(SensorFaultKind::SONAR_SILENT, 120.0));
  EXPECT_TRUE(faults.active(SensorFaultKind::SONAR_SILENT, 149.9));
  EXPECT_FALSE(faults.active(SensorFaultKind::SONAR_SILENT, 150.0));
  EXPECT_TRUE(faults.active(SensorFaultKind::DVL_LOST, 12.0));
  EXPECT_FALSE(faults.active(SensorFaultKind::DVL_LOST, 12.5));
  EXPECT_TRUE(faults.active(SensorFaultKind::NAVIGATION_SILENT, 0.5));
  EXPECT_FALSE(faults.active(SensorFaultKind::NAVIGATION_SILENT, 130.0));
  EXPECT_FALSE(SensorFaults().active(SensorFaultKind::SONAR_SILENT, 0.0));
  // Several to a string (a launch argument), none in an empty one.
  const SensorFaults listed = SensorFaults::parse({"sonar_silent@1+2  dvl_lost@5+1", ""});
  EXPECT_EQ(listed.faults().size(), 2u);
  EXPECT_TRUE(listed.active(SensorFaultKind::DVL_LOST, 5.5));
  EXPECT_TRUE(SensorFaults::parse({""}).empty());
}

TEST(SensorFaultsTest, NavigationJumpsAddUpFromTheirTime) {
  const SensorFaults faults =
      SensorFaults::parse({"navigation_jump@100:5,-3", "navigation_jump@200:-1,1"});
  EXPECT_EQ(faults.navigationOffset(99.0), Eigen::Vector2d(0, 0));
  EXPECT_EQ(faults.navigationOffset(100.0), Eigen::Vector2d(5, -3));
  EXPECT_EQ(faults.navigationOffset(500.0), Eigen::Vector2d(4, -2));
}

TEST(SensorFaultsTest, BadEntriesAreRefusedNamingThem) {
  const auto refused = [](const std::string& entry) {
    try {
      SensorFaults::parse({entry});
    } catch (const std::invalid_argument& error) {
      return std::string(error.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(refused("sonar_silent").find("'sonar_silent': expected KIND@T+D"), std::string::npos);
  EXPECT_NE(refused("gps_lost@1+2").find("unknown kind 'gps_lost'"), std::string::npos);
  EXPECT_NE(refused("sonar_silent@x+2").find("time 'x' is not a number"), std::string::npos);
  EXPECT_NE(refused("sonar_silent@1+0").find("duration must be > 0"), std::string::npos);
  EXPECT_NE(refused("sonar_silent@-1+2").find("time must be >= 0"), std::string::npos);
  EXPECT_NE(refused("sonar_silent@1").find("expected sonar_silent@T+D"), std::string::npos);
  EXPECT_NE(refused("navigation_jump@1:5").find("expected navigation_jump@T:DX,DY"),
            std::string::npos);
  EXPECT_NE(refused("navigation_jump@1:5,y").find("DY 'y' is not a number"), std::string::npos);
  EXPECT_NE(refused("dvl_lost@1+2nd").find("duration '2nd' is not a number"), std::string::npos);
}

}  // namespace
}  // namespace auv::sim
