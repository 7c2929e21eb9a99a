// `auv-recon`: the shore-side reconstruction commands, run as `auv recon <command>`.
#include <iostream>
#include <string>
#include <vector>

#include "auv/recon/tools/recon_cli.h"

namespace {
const char* kUsage =
    "usage: auv recon <command> [options]\n"
    "  pull --vehicle <name> --into <survey>/   pull the vehicle's recordings into the survey\n"
    "`auv recon <command> --help` for the options. DDS vendor and domain come from AUV_DDS and\n"
    "AUV_DOMAIN_ID, as for every `auv` command.\n";
}

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty() || args[0] == "--help" || args[0] == "-h") {
    std::cout << kUsage;
    return args.empty() ? 2 : 0;
  }
  const std::string command = args[0];
  args.erase(args.begin());
  if (command == "pull") return auv::recon::pullMain(args);
  std::cerr << "auv recon: unknown command '" << command << "'\n" << kUsage;
  return 2;
}
