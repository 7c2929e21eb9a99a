// Fuzz harness: launch files as `auv launch FILE [name:=value ...]` reads them
// (parseLaunchFile -> parseLaunchYaml: arguments and $(arg)/$(env) substitution, processes,
// inline parameters, the semantic check), once without and once with command-line arguments.
// A clear error is a LaunchFileError naming the file and the field; anything else (a crash, a
// sanitizer report, another exception) is a bug.
#include <cstdint>
#include <map>
#include <string>

#include "launch_description.h"

using auv::bringup::LaunchFileError;
using auv::bringup::parseLaunchYaml;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  try {
    parseLaunchYaml(input, "fuzz_launch.yaml", "/tmp");
  } catch (const LaunchFileError&) {
  }
  // The shipped launch files' arguments, set on the command line.
  const std::map<std::string, std::string> arguments = {{"world", "breakwater"}, {"seed", "2"}};
  try {
    parseLaunchYaml(input, "fuzz_launch.yaml", "/tmp", arguments);
  } catch (const LaunchFileError&) {
  }
  return 0;
}
