// `auv-sim`: the simulator's offline tool, also reachable as `auv sim <command>`.
#include <iostream>
#include <string>
#include <vector>

#include "auv/sim/tools/commands.h"

namespace {

void usage(std::ostream& out) {
  out << "usage: auv sim <command> [options]\n\n"
         "commands:\n"
         "  generate     generate procedural worlds (breakwater, canyon, ...) from a seed\n"
         "  check        validate a scenario file or a mesh and print a summary\n"
         "  render       render the camera videos of a simulated run from its trajectory\n"
         "  calibration  render underwater chessboard sequences for camera calibration\n"
         "  octomap      write a world's true occupancy as an OctoMap .bt (benchmarks)\n"
         "  mission      write a world's inspection mission file for `auv mission start`\n\n"
         "`auv sim <command> --help` describes a command.\n";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    usage(std::cerr);
    return 2;
  }
  const std::string command = argv[1];
  const std::vector<std::string> args(argv + 2, argv + argc);
  if (command == "-h" || command == "--help" || command == "help") {
    usage(std::cout);
    return 0;
  }
  if (command == "generate") return auv::sim::generateMain(args);
  if (command == "check") return auv::sim::checkMain(args);
  if (command == "render") return auv::sim::renderMain(args);
  if (command == "calibration") return auv::sim::calibrationMain(args);
  if (command == "octomap") return auv::sim::octomapMain(args);
  if (command == "mission") return auv::sim::missionMain(args);
  std::cerr << "auv sim: unknown command '" << command << "'\n";
  usage(std::cerr);
  return 2;
}
