#pragma once
// The simulator reads its scenario files with the project's strict YAML reader
// (auv/config/yaml_section.h) and reports bad input as the project's ConfigError (exit code 2).

#include "auv/config/errors.h"
#include "auv/config/yaml_section.h"

namespace auv::sim {

using config::ConfigError;
using config::loadYamlFile;
using config::requireOption;
using config::YamlSection;

}  // namespace auv::sim
