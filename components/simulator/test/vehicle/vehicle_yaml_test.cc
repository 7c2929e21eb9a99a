// The scenario's `vehicle:` section: read strictly, checked with the controller's model ranges,
// errors naming file and field.
#include "auv/sim/vehicle/vehicle.h"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <string>

namespace auv::sim {
namespace {

TEST(VehicleYaml, ReadsTheScenarioSectionStrictly) {
  const YAML::Node root = YAML::Load(
      "vehicle:\n"
      "  start: {position: [0, 0, 2], yaw: 0}\n"
      "  mass: 60\n"
      "  max_thrust_forward: 30\n"
      "  net_buoyancy: -1.5\n");
  const VehicleModel options =
      readVehicleModel(YamlSection(root["vehicle"], "vehicle", "test.yaml"));
  EXPECT_EQ(options.mass, 60);
  EXPECT_EQ(options.max_thrust_forward, 30);
  EXPECT_EQ(options.net_buoyancy, -1.5);
  EXPECT_EQ(options.drag_linear_surge, VehicleModel().drag_linear_surge);

  auto error = [](const std::string& text) {
    const YAML::Node node = YAML::Load(text);
    try {
      readVehicleModel(YamlSection(node["vehicle"], "vehicle", "test.yaml"));
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string typo = error("vehicle:\n  mas: 60\n");
  EXPECT_NE(typo.find("test.yaml: vehicle.mas"), std::string::npos) << typo;
  EXPECT_NE(typo.find("did you mean 'mass'"), std::string::npos) << typo;
  const std::string zero = error("vehicle:\n  mass: 0\n");
  EXPECT_NE(zero.find("test.yaml: vehicle.mass"), std::string::npos) << zero;
  const std::string word = error("vehicle:\n  thruster_spacing: wide\n");
  EXPECT_NE(word.find("vehicle.thruster_spacing"), std::string::npos) << word;
  // An absent section gives the defaults.
  EXPECT_EQ(readVehicleModel(YamlSection(YAML::Node(), "vehicle", "test.yaml")).mass,
            VehicleModel().mass);
}

}  // namespace
}  // namespace auv::sim
