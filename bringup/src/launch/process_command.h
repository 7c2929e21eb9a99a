#pragma once

#include "launch_description.h"

#include <map>
#include <string>
#include <vector>

namespace auv::bringup {

/// The concrete command line of one launch process and what the launch adds to its environment.
struct ProcessCommand {
  std::vector<std::string> argv;  // argv[0]: the program; the auv executable for components
  std::map<std::string, std::string> environment;  // launch env, then process env, then AUV_DDS
  std::string inline_params_path;  // generated params file; "" when there are no inline params
  std::string inline_params_yaml;  // content to write to inline_params_path
};

/// Resolves `process` of `launch` into argv and environment additions.
/// Components run as `<auv_executable> run <component>:<node> ... [--params <params_file>]
/// [--params <inline file>]`, the inline file being `<inline_params_dir>/<name>.params.yaml`
/// (passed last so inline values win). Commands get "auv" as argv[0] replaced by
/// `auv_executable`. Throws std::invalid_argument when the auv executable is needed but empty.
ProcessCommand buildProcessCommand(const LaunchDescription& launch,
                                   const ProcessDescription& process,
                                   const std::string& auv_executable,
                                   const std::string& inline_params_dir);

/// Params file content (node name -> parameters) for the inline parameters of `process`;
/// "" when none of its nodes has inline parameters. Quoted strings stay strings.
std::string inlineParametersYaml(const ProcessDescription& process);

/// "NAME=value" strings of `base` (an environ-style, null-terminated array; may be nullptr)
/// with `overrides` applied on top, sorted by name.
std::vector<std::string> mergeEnvironment(const char* const* base,
                                          const std::map<std::string, std::string>& overrides);

/// Looks `program` up like execvp would, but in the given PATH value (not the caller's).
/// Returns `program` unchanged when it contains '/', "" when nothing executable is found.
std::string findExecutable(const std::string& program, const std::string& path_variable);

/// Quotes `arg` so a POSIX shell reads it back unchanged (for display only).
std::string shellQuote(const std::string& arg);

/// argv joined with spaces, each argument shell-quoted when needed.
std::string formatCommand(const std::vector<std::string>& argv);

}  // namespace auv::bringup
