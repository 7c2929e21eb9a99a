#pragma once
// `auv sim generate`, kept in the worldgen library (streams passed in) so tests can run it;
// tools/generate_command.cc forwards generateMain() here.

#include <ostream>
#include <string>
#include <vector>

namespace auv::sim {

/// Runs `auv sim generate <world|all> [--seed N] [--out DIR] [--detail X] [--texture-size N]`
/// (or `--list`, `--help`). Returns 0 on success, 1 when writing fails, 2 on a usage error;
/// errors are one line on `err`, prefixed "auv sim generate: ".
int runGenerateCommand(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace auv::sim
