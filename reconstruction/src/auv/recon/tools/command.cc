#include "auv/recon/tools/command.h"

#include <algorithm>
#include <iostream>
#include <stdexcept>

#include "auv/recon/common/stage_error.h"

namespace auv::recon::tools {

namespace {
std::vector<Command>& registry() {
  static std::vector<Command> commands;
  return commands;
}
}  // namespace

std::vector<Command> commands() {
  std::vector<Command> sorted = registry();
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](const Command& a, const Command& b) { return a.order < b.order; });
  return sorted;
}

CommandRegistrar::CommandRegistrar(std::string name, int order, std::string summary,
                                   std::function<int(const std::vector<std::string>&)> run) {
  registry().push_back({std::move(name), order, std::move(summary), std::move(run)});
}

int runReportingErrors(const std::string& command, const std::function<int()>& body) {
  try {
    return body();
  } catch (const std::exception& e) {
    // OptionError, bad usage: 2; StageError, I/O: 1 (auv/config/errors.h).
    const int code = config::exitCodeFor(e);
    std::cerr << "auv recon " << command << ": " << (code == kExitUsage ? "" : "error: ")
              << e.what() << "\n";
    return code;
  }
}

}  // namespace auv::recon::tools
