#pragma once
// Subcommands of `auv-mission` (run as `auv mission <command>`): each returns the exit code
// (0 ok, 1 runtime failure, 2 usage or input error) and prints one clear line on errors.

#include <string>
#include <vector>

namespace auv::mission {

/// `auv mission start <mission.yaml> [--id ID] [--wait] [--timeout S]`
int startMain(const std::vector<std::string>& args);
/// `auv mission status [--follow] [--timeout S]`
int statusMain(const std::vector<std::string>& args);
/// `auv mission abort [--reason TEXT] [--timeout S]`
int abortMain(const std::vector<std::string>& args);
/// `auv mission report <run-dir> [--out DIR]`: the mission figure (SVG) and summary (JSON).
int reportMain(const std::vector<std::string>& args);

}  // namespace auv::mission
