// `auv-mission`: mission commands for the vehicle's mission handler, run as `auv mission ...`.
#include <iostream>
#include <string>
#include <vector>

#include "auv/mission/tools/mission_cli.h"

namespace {
const char* kUsage =
    "usage: auv mission <command> [options]\n"
    "  start <mission.yaml>  send a mission to the mission handler (--wait: follow it to the end)\n"
    "  status                the latest mission/status (--follow: until the mission ends)\n"
    "  abort                 abort the running mission: the vehicle stops and keeps its depth\n"
    "  report <run-dir>      mission figure (SVG) and summary (JSON) from a run folder\n"
    "DDS vendor and domain come from AUV_DDS and AUV_DOMAIN_ID, as for every `auv` command.\n";
}

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty() || args[0] == "--help" || args[0] == "-h") {
    std::cout << kUsage;
    return args.empty() ? 2 : 0;
  }
  const std::string command = args[0];
  args.erase(args.begin());
  if (command == "start") return auv::mission::startMain(args);
  if (command == "status") return auv::mission::statusMain(args);
  if (command == "abort") return auv::mission::abortMain(args);
  if (command == "report") return auv::mission::reportMain(args);
  std::cerr << "auv mission: unknown command '" << command << "'\n" << kUsage;
  return 2;
}
