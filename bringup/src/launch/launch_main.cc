#include "launch_main.h"

#include "launch_description.h"
#include "process_command.h"
#include "supervisor.h"

#include <cstdlib>
#include <exception>
#include <filesystem>
#include <iostream>
#include <map>
#include <sstream>

extern char** environ;

namespace auv::bringup {
namespace {

constexpr int kUsageError = 2;  // bad arguments or invalid launch file
constexpr int kSetupError = 1;  // valid launch that could not be set up
constexpr const char* kUsage = "usage: auv launch <file.yaml> [name:=value ...] [--dry-run]";

std::string describeRestart(const ProcessDescription& process) {
  std::ostringstream out;
  out << toString(process.restart);
  if (process.restart != RestartPolicy::NEVER) {
    out << " (max_restarts: "
        << (process.max_restarts ? std::to_string(*process.max_restarts) : "unlimited")
        << ", restart_delay: " << process.restart_delay << " s)";
  }
  return out.str();
}

// Prints what `auv launch` would run, without running or writing anything.
void printDryRun(const LaunchDescription& launch, const std::string& auv_executable,
                 std::ostream& out) {
  const char* tmpdir = std::getenv("TMPDIR");
  const std::string params_dir =
      (std::filesystem::path(tmpdir != nullptr && *tmpdir != '\0' ? tmpdir : "/tmp") /
       "auv-launch-XXXXXX")
          .string();
  out << "# " << launch.source << ": " << launch.processes.size()
      << " process(es), shutdown_timeout: " << launch.shutdown_timeout << " s\n";
  for (const LaunchArgument& a : launch.arguments) {
    out << "# argument " << a.name << " := " << a.default_value
        << (a.description.empty() ? "" : "  (" + a.description + ")") << "\n";
  }
  for (const ProcessDescription& process : launch.processes) {
    const ProcessCommand command = buildProcessCommand(launch, process, auv_executable, params_dir);
    out << process.name << ":\n";
    out << "  command: " << formatCommand(command.argv) << "\n";
    std::string path_variable;
    for (const std::string& entry : mergeEnvironment(environ, command.environment)) {
      if (entry.rfind("PATH=", 0) == 0) path_variable = entry.substr(5);
    }
    if (findExecutable(command.argv[0], path_variable).empty()) {
      out << "  warning: '" << command.argv[0] << "' not found in PATH\n";
    }
    out << "  environment:";
    if (command.environment.empty()) out << " (inherited only)";
    for (const auto& [name, value] : command.environment) {
      out << " " << shellQuote(name + "=" + value);
    }
    out << "\n";
    out << "  restart: " << describeRestart(process)
        << "\n  required: " << (process.required ? "true" : "false") << "\n";
    if (!command.inline_params_yaml.empty()) {
      out << "  inline parameters (" << command.inline_params_path << "):\n";
      std::istringstream lines(command.inline_params_yaml);
      for (std::string line; std::getline(lines, line);) out << "    " << line << "\n";
    }
  }
}

}  // namespace

int launchMain(const std::vector<std::string>& args, const std::string& auv_executable) {
  std::string file;
  bool dry_run = false;
  std::map<std::string, std::string> arguments;
  for (const std::string& arg : args) {
    if (arg == "--dry-run") {
      dry_run = true;
    } else if (arg == "-h" || arg == "--help") {
      std::cout << kUsage << "\n"
                << "Starts and supervises the processes described in <file.yaml>.\n"
                << "  name:=value  set a launch argument declared in the file's `arguments:`\n"
                << "  --dry-run    print the arguments, resolved commands and environments;\n"
                << "               run nothing\n";
      return 0;
    } else if (!arg.empty() && arg[0] == '-') {
      std::cerr << "auv launch: unknown option '" << arg << "' (" << kUsage << ")\n";
      return kUsageError;
    } else if (!file.empty() && arg.find(":=") != std::string::npos) {
      const size_t at = arg.find(":=");
      arguments[arg.substr(0, at)] = arg.substr(at + 2);
    } else if (!file.empty()) {
      std::cerr << "auv launch: unexpected argument '" << arg << "' (" << kUsage << ")\n";
      return kUsageError;
    } else {
      file = arg;
    }
  }
  if (file.empty()) {
    std::cerr << "auv launch: missing launch file (" << kUsage << ")\n";
    return kUsageError;
  }

  LaunchDescription launch;
  try {
    launch = parseLaunchFile(file, arguments);
  } catch (const LaunchFileError& e) {
    std::cerr << "auv launch: " << e.what() << "\n";
    return kUsageError;
  }

  try {
    if (dry_run) {
      printDryRun(launch, auv_executable, std::cout);
      return 0;
    }
    SupervisorOptions options;
    options.auv_executable = auv_executable;
    std::cout.flush();
    Supervisor supervisor(std::move(launch), options);
    return supervisor.run().exit_code;
  } catch (const std::exception& e) {
    const int code = config::exitCodeFor(e);
    std::cerr << "auv launch: " << (code == kUsageError ? file + ": " : "") << e.what() << "\n";
    return code;
  }
}

}  // namespace auv::bringup
