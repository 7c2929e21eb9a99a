#pragma once
// Shared pieces of the `auv` sub-commands: argument parsing and one-line errors.

#include <chrono>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "auv/config/errors.h"

namespace auv::bringup {

/// A user error: printed as one line "auv <command>: <message>", exit code 2 (usage/input)
/// or 1 (runtime, e.g. no data within the timeout).
class CliError : public config::Error {
 public:
  CliError(const std::string& message, int exit_code = config::ConfigError::kExitCode)
      : config::Error(message), exit_code_(exit_code) {}
  int exitCode() const override { return exit_code_; }

 private:
  int exit_code_;
};

/// Minimal argv parser: positional arguments plus `--flag`, `--option value` and `-x value`.
/// `-h` and `--help` are accepted by every command (helpRequested()).
class Args {
 public:
  Args(std::vector<std::string> args, std::vector<std::string> flags,
       std::vector<std::string> options);
  bool flag(const std::string& name) const;
  std::optional<std::string> option(const std::string& name) const;
  double number(const std::string& name, double fallback) const;
  const std::vector<std::string>& positional() const { return positional_; }
  bool helpRequested() const { return help_; }
  /// The i-th positional argument; throws CliError naming `what` when missing.
  const std::string& at(size_t i, const std::string& what) const;

 private:
  std::vector<std::string> positional_;
  std::vector<std::string> flags_set_;
  std::vector<std::pair<std::string, std::string>> options_set_;
  bool help_ = false;
};

/// "/chatter" for "chatter" or "/chatter".
std::string displayTopic(const std::string& topic);

int topicMain(const std::vector<std::string>& args);
int nodeMain(const std::vector<std::string>& args);
int runMain(const std::vector<std::string>& args);
int interfaceMain(const std::vector<std::string>& args);

}  // namespace auv::bringup
