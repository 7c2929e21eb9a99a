// The world's mission file: the scenario's `mission:` section decides between the paper's
// fixed-depth mode and 3-D planning inside a depth band.
#include "auv/sim/world/mission_export.h"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>

#include "test_meshes.h"

namespace auv::sim {
namespace {

namespace fs = std::filesystem;

class MissionExportTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("auv_mission_export_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    saveMesh(test::box({0, 0, -10}, {2, 3, -1}), (dir_ / "block.ply").string());
  }
  void TearDown() override { fs::remove_all(dir_); }
  YAML::Node exported(const std::string& extra, std::string* text = nullptr) {
    const std::string path = (dir_ / "scenario.yaml").string();
    std::ofstream(path) << "world: {mesh: block.ply, seabed_depth: 10}\n"
                        << "vehicle: {start: {position: [-5, 1, 3]}}\n"
                        << "queries: [{name: a, goal: [8, 1, 4]}]\n"
                        << extra;
    const Scenario scenario = loadScenario(path);
    const std::string yaml = missionYaml(scenario, loadWorldMesh(scenario));
    if (text) *text = yaml;
    return YAML::Load(yaml)["mission"]["defaults"];
  }
  fs::path dir_;
};

TEST_F(MissionExportTest, FixedDepthByDefaultAtTheStartDepth) {
  std::string text;
  const YAML::Node defaults = exported("", &text);
  EXPECT_TRUE(defaults["fixed_depth"].as<bool>());
  EXPECT_DOUBLE_EQ(defaults["depth"].as<double>(), 3.0);
  EXPECT_FALSE(defaults["min_depth"]);
  EXPECT_FALSE(defaults["max_depth"]);
  EXPECT_FALSE(defaults["min_altitude"]);
  // The file says when to use which mode.
  EXPECT_NE(text.find("# fixed_depth: true plans in one horizontal plane"), std::string::npos);
  EXPECT_NE(text.find("false plans in 3-D"), std::string::npos);
}

TEST_F(MissionExportTest, ThreeDimensionalWorldsWriteTheirBandAndNoDepth) {
  const YAML::Node defaults =
      exported("mission: {fixed_depth: false, min_depth: 2, max_depth: 8, min_altitude: 1.5}\n");
  EXPECT_FALSE(defaults["fixed_depth"].as<bool>());
  EXPECT_FALSE(defaults["depth"]) << "no fixed plane in 3-D";
  EXPECT_DOUBLE_EQ(defaults["min_depth"].as<double>(), 2.0);
  EXPECT_DOUBLE_EQ(defaults["max_depth"].as<double>(), 8.0);
  EXPECT_DOUBLE_EQ(defaults["min_altitude"].as<double>(), 1.5);
  // The bounds stay the outer limits: surface to seabed.
  EXPECT_DOUBLE_EQ(defaults["bounds"]["min"][2].as<double>(), 0.0);
  EXPECT_DOUBLE_EQ(defaults["bounds"]["max"][2].as<double>(), 10.0);
}

TEST_F(MissionExportTest, ThreeDimensionalWithoutBandWritesOnlyTheMode) {
  const YAML::Node defaults = exported("mission: {fixed_depth: false}\n");
  EXPECT_FALSE(defaults["fixed_depth"].as<bool>());
  EXPECT_FALSE(defaults["depth"]);
  EXPECT_FALSE(defaults["min_depth"]);
  EXPECT_FALSE(defaults["min_altitude"]);
}

}  // namespace
}  // namespace auv::sim
