// `auv`: the command-line tool of auv-inspect, modelled on ros2cli.
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "auv/interfaces/parameters.h"
#include "cli/cli_common.h"
#include "launch/launch_main.h"

namespace {

constexpr const char* kUsage =
    "usage: auv <command> ...\n"
    "  topic list|info|echo|hz|bw|pub   inspect and publish topics (`auv topic` for details)\n"
    "  node list                        nodes on the domain, of both DDS vendors\n"
    "  interface list|show              message types and their fields\n"
    "  run <component>[:name] ...       run components (several: composed in one process)\n"
    "  launch <file.yaml>               start and supervise processes from a launch file\n"
    "  sim generate|check|render|...    simulator tools (`auv sim --help`)\n"
    "  mission start|status|abort|report   run and inspect missions (`auv mission --help`)\n"
    "  recon pull                       shore: pull a vehicle's recordings (`auv recon --help`)\n"
    "  security init|add|list|check     DDS Security keystores (`auv security --help`)\n"
    "  bag record|play|info             MCAP bags of any topics (`auv bag record --help`)\n"
    "  view <folder> | --live           a survey, a run or a live mission in the browser\n"
    "Other commands run the program `auv-<command>` (next to `auv`, in a sibling install\n"
    "prefix, or on PATH), like git; `auv <command> <sub>` runs `auv-<command>-<sub>` first\n"
    "where that program exists.\n"
    "Environment: AUV_DDS=cyclonedds|fastdds (default cyclonedds), AUV_DOMAIN_ID (default 0).\n";

std::string selfExecutable(const char* argv0) {
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::string(argv0) : exe.string();
}

// `auv <command>` for a command of another package: the program auv-<command> next to this
// one, in a sibling prefix of an isolated colcon install (<prefix>/../*/bin), or on PATH.
std::string findExternalCommand(const std::string& command, const std::string& self) {
  namespace fs = std::filesystem;
  const std::string name = "auv-" + command;
  if (command.empty() || command.find('/') != std::string::npos) return "";
  const auto executable = [](const fs::path& p) {
    std::error_code ec;
    return fs::is_regular_file(p, ec) && ::access(p.c_str(), X_OK) == 0;
  };
  const fs::path bin = fs::path(self).parent_path();
  if (executable(bin / name)) return (bin / name).string();
  std::error_code ec;
  for (const auto& prefix : fs::directory_iterator(bin.parent_path().parent_path(), ec)) {
    if (executable(prefix.path() / "bin" / name)) return (prefix.path() / "bin" / name).string();
  }
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "";
  size_t start = 0;
  while (start <= dirs.size()) {
    const size_t end = dirs.find(':', start);
    const std::string dir =
        dirs.substr(start, end == std::string::npos ? std::string::npos : end - start);
    if (!dir.empty() && executable(fs::path(dir) / name)) return (fs::path(dir) / name).string();
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return "";
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty() || args[0] == "-h" || args[0] == "--help") {
    std::cout << kUsage;
    return args.empty() ? 2 : 0;
  }
  const std::string command = args[0];
  const std::vector<std::string> rest(args.begin() + 1, args.end());
  try {
    if (command == "topic") return auv::bringup::topicMain(rest);
    if (command == "node") return auv::bringup::nodeMain(rest);
    if (command == "interface") return auv::bringup::interfaceMain(rest);
    if (command == "run") return auv::bringup::runMain(rest);
    if (command == "launch") return auv::bringup::launchMain(rest, selfExecutable(argv[0]));
    const std::string self = selfExecutable(argv[0]);
    // `auv <command> <subcommand>` runs auv-<command>-<subcommand> where that program exists:
    // a lean program for a subcommand that should start at once (auv-recon-pull links DDS and
    // the transfer alone; auv-recon loads the whole reconstruction stack, 0.17 s of start-up).
    std::string external;
    int first_argument = 2;
    if (!rest.empty() && !rest[0].empty() && rest[0][0] != '-') {
      external = findExternalCommand(command + "-" + rest[0], self);
      if (!external.empty()) first_argument = 3;
    }
    if (external.empty()) external = findExternalCommand(command, self);
    if (!external.empty()) {
      std::vector<char*> external_argv;
      external_argv.push_back(const_cast<char*>(external.c_str()));
      for (int i = first_argument; i < argc; ++i) external_argv.push_back(argv[i]);
      external_argv.push_back(nullptr);
      ::execv(external.c_str(), external_argv.data());
      std::cerr << "auv: cannot run " << external << ": " << std::strerror(errno) << std::endl;
      return 1;
    }
    std::cerr << "auv: unknown command '" << command << "'\n" << kUsage;
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "auv " << command << ": " << e.what() << std::endl;
    return auv::config::exitCodeFor(e);  // input errors 2, failures 1
  }
}
