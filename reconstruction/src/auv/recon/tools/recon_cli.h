#pragma once
// Subcommands of `auv-recon` (`auv recon <command>`), one function each.

#include <string>
#include <vector>

namespace auv::recon {

/// `auv recon pull --vehicle <name> --into <survey>/ [options]`; returns the exit code.
int pullMain(const std::vector<std::string>& args);

}  // namespace auv::recon
