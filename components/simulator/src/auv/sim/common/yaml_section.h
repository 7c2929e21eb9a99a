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

/// Runs the options' cross-field check() and prefixes its message with the scenario file, so the
/// one-line error names both the file and the field ("scenario.yaml: multibeam.rows: ...").
template <typename Options>
void checkInFile(const YamlSection& section, const Options& options) {
  try {
    options.check();
  } catch (const ConfigError& e) {
    throw ConfigError(section.file() + ": " + e.what());
  }
}

}  // namespace auv::sim
