#pragma once

#include <string>
#include <vector>

namespace auv::bringup {

/// Entry point of `auv launch <file.yaml> [--dry-run]`.
///
/// @param[in] args            the words after "launch", e.g. {"demo.yaml", "--dry-run"}
/// @param[in] auv_executable  absolute path of the running auv executable (resolved
///                            /proc/self/exe); used for components and for "auv" in commands
/// @return the process exit code: the launch's (see Supervisor::run()), 0 for --help and
///         --dry-run, 2 for bad arguments or an invalid launch file, 1 when the launch cannot
///         be set up. Errors are reported as one line on stderr starting with "auv launch: ".
int launchMain(const std::vector<std::string>& args, const std::string& auv_executable);

}  // namespace auv::bringup
