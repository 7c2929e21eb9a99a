// `auv`: the command-line tool of auv-inspect, modelled on ros2cli.
#include <unistd.h>

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
    "Environment: AUV_DDS=cyclonedds|fastdds (default cyclonedds), AUV_DOMAIN_ID (default 0).\n";

std::string selfExecutable(const char* argv0) {
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::string(argv0) : exe.string();
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
    std::cerr << "auv: unknown command '" << command << "'\n" << kUsage;
    return 2;
  } catch (const auv::bringup::CliError& e) {
    std::cerr << "auv " << command << ": " << e.what() << std::endl;
    return e.exitCode();
  } catch (const std::invalid_argument& e) {
    std::cerr << "auv " << command << ": " << e.what() << std::endl;
    return 2;
  } catch (const auv::interfaces::ParameterError& e) {
    std::cerr << "auv " << command << ": " << e.what() << std::endl;
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "auv " << command << ": " << e.what() << std::endl;
    return 1;
  }
}
