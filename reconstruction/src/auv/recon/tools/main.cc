// `auv-recon`: the shore-side reconstruction commands, run as `auv recon <command>`.
#include <iomanip>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "auv/recon/tools/command.h"

namespace {
std::string usage() {
  std::ostringstream out;
  out << "usage: auv recon <command> [options]\n";
  for (const auto& command : auv::recon::tools::commands()) {
    out << "  " << std::left << std::setw(11) << command.name << command.summary << "\n";
  }
  out << "`auv recon <command> --help` for the options. The survey folder layout is in\n"
         "reconstruction/README.md. DDS vendor and domain (pull) come from AUV_DDS and\n"
         "AUV_DOMAIN_ID, as for every `auv` command.\n";
  return out.str();
}
}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  // A program built with one command (auv-recon-pull) is that command: no name to give.
  const auto all = auv::recon::tools::commands();
  if (all.size() == 1) return all.front().run(args);
  if (args.empty() || args[0] == "--help" || args[0] == "-h") {
    std::cout << usage();
    return args.empty() ? auv::recon::tools::kExitUsage : 0;
  }
  const std::string name = args[0];
  args.erase(args.begin());
  for (const auto& command : all) {
    if (command.name == name) return command.run(args);
  }
  std::cerr << "auv recon: unknown command '" << name << "'\n" << usage();
  return auv::recon::tools::kExitUsage;
}
