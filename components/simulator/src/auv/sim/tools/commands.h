#pragma once
// Subcommands of the `auv-sim` tool (run as `auv sim <command> ...`). Each takes the arguments
// after its name, prints its own --help, and returns the process exit code (0 ok, 1 runtime
// failure, 2 usage error); errors are one clear line on stderr.

#include <string>
#include <vector>

namespace auv::sim {

/// `auv sim generate <world|all> [--seed N] [--out DIR] ...`: procedural worlds.
int generateMain(const std::vector<std::string>& args);
/// `auv sim render <run-dir> [--cameras a,b] [--threads N] ...`: camera videos from a logged run.
int renderMain(const std::vector<std::string>& args);
/// `auv sim calibration <scenario|world> --out DIR ...`: underwater chessboard sequences.
int calibrationMain(const std::vector<std::string>& args);
/// `auv sim check <scenario.yaml|mesh>`: validates a scenario or mesh and prints a summary.
int checkMain(const std::vector<std::string>& args);
/// `auv sim octomap <world|scenario.yaml> --out map.bt ...`: the world's true occupancy (.bt).
int octomapMain(const std::vector<std::string>& args);
/// `auv sim mission <world|scenario> [--seed N] [--out FILE]`: the world's mission file.
int missionMain(const std::vector<std::string>& args);

}  // namespace auv::sim
