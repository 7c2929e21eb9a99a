#pragma once
// Launch arguments, as in ROS 2 launch: a launch file declares them under `arguments:`
//
//   arguments:
//     world: {default: canyon, description: "world name or scenario file"}
//     seed: {default: "1"}
//     rate: {description: "required: no default"}
//
// the command line sets them (`auv launch sim.yaml world:=breakwater`), and `$(arg world)`
// anywhere inside a string of the file is replaced by the value before the file is checked.

#include <yaml-cpp/yaml.h>

#include <map>
#include <string>
#include <vector>

namespace auv::bringup {

struct LaunchArgument {
  std::string name;
  std::string default_value;
  bool has_default = false;
  std::string description;
};

/// Reads `arguments:` (removing it from `root`), checks `given` against the declarations,
/// and replaces every `$(arg name)` in the remaining strings. Throws LaunchFileError naming the
/// file and field for an undeclared, missing or malformed argument. Returns the declarations
/// with their resolved values in `default_value`.
std::vector<LaunchArgument> applyLaunchArguments(YAML::Node& root,
                                                 const std::map<std::string, std::string>& given,
                                                 const std::string& source);

}  // namespace auv::bringup
