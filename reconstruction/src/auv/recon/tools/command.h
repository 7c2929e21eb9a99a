#pragma once
// `auv recon <command>`: every tools/<name>_command.cc registers its command with
// AUV_RECON_COMMAND, so adding a stage does not touch main.cc.

#include <functional>
#include <string>
#include <vector>

namespace auv::recon::tools {

/// Exit codes shared by the commands.
constexpr int kExitOk = 0;
constexpr int kExitFailed = 1;  ///< the stage could not do its work (StageError), I/O errors
constexpr int kExitUsage = 2;   ///< bad command line or option value

struct Command {
  std::string name;
  int order = 0;  ///< place in the usage list (pipeline order)
  std::string summary;
  std::function<int(const std::vector<std::string>& args)> run;
};

/// All registered commands, in `order`.
std::vector<Command> commands();

struct CommandRegistrar {
  CommandRegistrar(std::string name, int order, std::string summary,
                   std::function<int(const std::vector<std::string>&)> run);
};

/// Runs `body` and turns exceptions into an error line on stderr and an exit code:
/// OptionError / std::invalid_argument -> 2, everything else -> 1. `command` prefixes the line.
int runReportingErrors(const std::string& command, const std::function<int()>& body);

}  // namespace auv::recon::tools

#define AUV_RECON_CONCAT_INNER(a, b) a##b
#define AUV_RECON_CONCAT(a, b) AUV_RECON_CONCAT_INNER(a, b)
/// Registers `function` (int(const std::vector<std::string>&)) as `auv recon <name>`.
#define AUV_RECON_COMMAND(name, order, summary, function)              \
  static const ::auv::recon::tools::CommandRegistrar AUV_RECON_CONCAT( \
      auv_recon_command_, __LINE__)(name, order, summary, function)
