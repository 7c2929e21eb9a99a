// `auv sim generate <world|all> ...`: procedural worlds (the work is in the worldgen library).
#include <iostream>

#include "auv/sim/tools/commands.h"
#include "auv/sim/worldgen/generate_cli.h"

namespace auv::sim {

int generateMain(const std::vector<std::string>& args) {
  return runGenerateCommand(args, std::cout, std::cerr);
}

}  // namespace auv::sim
