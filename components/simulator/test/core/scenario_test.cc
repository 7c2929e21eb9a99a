// Scenario files: frames, water optics, and errors that name the file and field.
#include "auv/sim/world/scenario.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "test_meshes.h"

namespace auv::sim {
namespace {

namespace fs = std::filesystem;

class ScenarioTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("auv_scenario_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    saveMesh(test::box({0, 0, -10}, {2, 3, -1}), (dir_ / "block.ply").string());
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& text) {
    const std::string p = (dir_ / "scenario.yaml").string();
    std::ofstream(p) << text;
    return p;
  }
  std::string errorOf(const std::string& text) {
    try {
      loadScenario(write(text));
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "";
  }
  fs::path dir_;
};

TEST_F(ScenarioTest, ReadsEverySectionAndResolvesTheMeshNextToTheFile) {
  const Scenario s = loadScenario(write(R"(
name: blocks
world: {mesh: block.ply, up_axis: z, origin: [1, 2, 0], seabed_depth: 10}
water: {visibility: 5}
vehicle: {start: {position: [0, -5, 3], yaw_deg: 90}}
queries:
  - {name: cross, goal: [0, 8, 3], tolerance: 2}
  - {goal: [4, 4, 4]}
)"));
  EXPECT_EQ(s.name, "blocks");
  EXPECT_EQ(s.mesh_path, (dir_ / "block.ply").string());
  EXPECT_NEAR(s.start_yaw, M_PI / 2, 1e-12);
  ASSERT_EQ(s.queries.size(), 2u);
  EXPECT_EQ(s.queries[1].name, "query2");
  EXPECT_DOUBLE_EQ(s.queries[0].tolerance, 2.0);
  EXPECT_NEAR(s.water.attenuation.y(), 3.912 / 5, 1e-12);
}

TEST_F(ScenarioTest, ZUpMeshesLandInNedWithTheSurfaceAtDepthZero) {
  const Scenario s = loadScenario(write("world: {mesh: block.ply, origin: [1, 2, 0]}\n"));
  const Mesh world = loadWorldMesh(s);
  const Eigen::AlignedBox3f box = meshBounds(world);
  // Mesh z in [-10, -1] (up) becomes depth [1, 10]; y flips (west -> east).
  EXPECT_NEAR(box.min().z(), 1.0f, 1e-5);
  EXPECT_NEAR(box.max().z(), 10.0f, 1e-5);
  EXPECT_NEAR(box.min().x(), 1.0f, 1e-5);
  EXPECT_NEAR(box.min().y(), 2.0f - 3.0f, 1e-5);
  EXPECT_NEAR(box.max().y(), 2.0f, 1e-5);
}

TEST_F(ScenarioTest, VisibilityLosesRedFirst) {
  const WaterOptics w = WaterOptics::fromVisibility(4.5);
  EXPECT_GT(w.attenuation.x(), w.attenuation.z());
  EXPECT_GT(w.attenuation.z(), w.attenuation.y());
  // Green contrast exp(-c d) is 2 % at the visibility distance.
  EXPECT_NEAR(std::exp(-w.attenuation.y() * 4.5), 0.02, 1e-3);
}

TEST_F(ScenarioTest, ErrorsNameTheFileAndField) {
  EXPECT_NE(errorOf("world: {mesh: block.ply}\nwater: {visibility: far}\n")
                .find("scenario.yaml: water.visibility: expected a finite number"),
            std::string::npos);
  EXPECT_NE(errorOf("world: {mesh: block.ply}\nwater: {visibility: -3}\n").find("water.visibility"),
            std::string::npos);
  EXPECT_NE(errorOf("world: {mesh: missing.obj}\n").find("world.mesh: no such file"),
            std::string::npos);
  // A name the file system refuses threw std::filesystem::filesystem_error.
  EXPECT_NE(errorOf("world: {mesh: " + std::string(300, 'm') + ".obj}\n").find("world.mesh: "),
            std::string::npos);
  EXPECT_NE(errorOf("world: {mesh: block.ply/inside.obj}\n").find("world.mesh: no such file"),
            std::string::npos);
  EXPECT_NE(errorOf("name: x\n").find("world.mesh: missing"), std::string::npos);
  EXPECT_NE(errorOf("world: {mesh: block.ply, up_axis: q}\n").find("world.up_axis"),
            std::string::npos);
  EXPECT_NE(errorOf("world: {mesh: block.ply}\nqueries: [{goal: [1, 2]}]\n")
                .find("queries[0].goal: expected 3 numbers"),
            std::string::npos);
  EXPECT_NE(errorOf("world: {mesh: block.ply}\nvehicle: {start: {position: [0, 0, -2]}}\n")
                .find("vehicle.start.position"),
            std::string::npos);
  EXPECT_NE(errorOf("world: {mesh: block.ply}\nwater: {visibilty: 3}\n")
                .find("did you mean 'visibility'"),
            std::string::npos);
  EXPECT_NE(errorOf("world: [1, 2]\n").find("world: expected a map"), std::string::npos);
  // file:line:column, as parameter and launch files
  const std::string syntax = errorOf("world: {mesh: block.ply\n");
  EXPECT_NE(syntax.find("scenario.yaml:2:"), std::string::npos) << syntax;
  EXPECT_NE(syntax.find(": malformed YAML: "), std::string::npos) << syntax;
}

TEST_F(ScenarioTest, MissionSectionSaysHowTheWorldPlans) {
  const Scenario plain = loadScenario(write("world: {mesh: block.ply, seabed_depth: 10}\n"));
  EXPECT_TRUE(plain.mission.fixed_depth);  // the paper's 2-D mode unless a scenario says else
  EXPECT_FALSE(plain.mission.hasBand());
  const Scenario s = loadScenario(write(R"(
world: {mesh: block.ply, seabed_depth: 10}
mission: {fixed_depth: false, min_depth: 2, max_depth: 8, min_altitude: 1.5}
)"));
  EXPECT_FALSE(s.mission.fixed_depth);
  EXPECT_DOUBLE_EQ(s.mission.min_depth, 2.0);
  EXPECT_DOUBLE_EQ(s.mission.max_depth, 8.0);
  EXPECT_DOUBLE_EQ(s.mission.min_altitude, 1.5);
}

TEST_F(ScenarioTest, MissionSectionErrorsNameTheFileAndField) {
  const std::string world = "world: {mesh: block.ply, seabed_depth: 10}\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"mission: {fixed_depth: maybe}", "scenario.yaml: mission.fixed_depth"},
      {"mission: {min_depth: 5, max_depth: 3}",
       "scenario.yaml: mission.max_depth: must be greater"},
      {"mission: {min_depth: 4, max_depth: 4}", "mission.max_depth: must be greater"},
      {"mission: {min_depth: 2, max_depth: 12}", "mission.max_depth: must be inside the water"},
      {"mission: {min_depth: -1, max_depth: 5}", "mission.min_depth: must be inside the water"},
      {"mission: {min_depth: 2}", "mission.max_depth: missing"},
      {"mission: {max_depth: 2}", "mission.min_depth: missing"},
      {"mission: {min_altitude: -0.5}", "scenario.yaml: mission.min_altitude: must be >= 0"},
      {"mission: {min_altitud: 1}", "did you mean 'min_altitude'"},
      {"mission: {min_depth: deep, max_depth: 5}", "mission.min_depth: expected a finite number"},
  };
  for (const auto& [section, expected] : cases) {
    const std::string error = errorOf(world + section + "\n");
    EXPECT_NE(error.find(expected), std::string::npos) << section << " -> " << error;
  }
}

}  // namespace
}  // namespace auv::sim
