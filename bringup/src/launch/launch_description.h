#pragma once

#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "launch_arguments.h"

#include "auv/config/errors.h"

namespace auv::bringup {

/// What the supervisor does when a process exits on its own.
enum class RestartPolicy {
  NEVER,       // leave it dead (default)
  ON_FAILURE,  // restart after a non-zero exit, a signal or a failed start
  ALWAYS,      // restart after any exit, including exit code 0
};

/// DDS implementation selected per process through the AUV_DDS environment variable.
enum class DdsVendor {
  DEFAULT,     // AUV_DDS is left as inherited
  CYCLONEDDS,  // AUV_DDS=cyclonedds
  FASTDDS,     // AUV_DDS=fastdds
};

/// How a process is started.
enum class ProcessKind {
  COMPONENT,    // `auv run <component>:<process name>`
  COMPOSITION,  // `auv run <c1>:<n1> <c2>:<n2> ...`, composed in one process
  COMMAND,      // arbitrary argv; "auv" as argv[0] is this same auv executable
};

/// Spelling used in launch files ("never", "on-failure", "always").
const char* toString(RestartPolicy policy);
/// Spelling used in launch files and in AUV_DDS ("cyclonedds", "fastdds"; "" for DEFAULT).
const char* toString(DdsVendor vendor);

/// One node of a component or composition process.
struct ComponentDescription {
  std::string component;  // component type, as accepted by `auv run`
  std::string node_name;  // node name; keys this node's parameters in params files
  YAML::Node parameters;  // inline parameters (a mapping), null when none
};

/// One supervised OS process.
struct ProcessDescription {
  std::string name;  // unique in the launch; prefixes the output lines as "[name] "
  ProcessKind kind = ProcessKind::COMMAND;
  std::vector<ComponentDescription> components;  // COMPONENT (exactly one) or COMPOSITION
  std::vector<std::string> command;              // COMMAND: argv, argv[0] searched in PATH
  DdsVendor vendor = DdsVendor::DEFAULT;
  std::string params_file;  // absolute path or empty; passed before the inline parameters
  std::map<std::string, std::string> environment;  // on top of the launch-level environment
  RestartPolicy restart = RestartPolicy::NEVER;
  std::optional<int> max_restarts;  // restarts allowed; unset = unlimited
  double restart_delay = 1.0;       // [s] between an exit and the restart
  bool required = false;            // its final exit ends the whole launch
};

/// A parsed launch file.
struct LaunchDescription {
  std::string source;    // launch file path as given by the user, used in messages
  std::string base_dir;  // absolute folder of the launch file; relative paths resolve here
  std::map<std::string, std::string> environment;  // for all processes
  double shutdown_timeout = 5.0;  // [s] SIGINT -> SIGTERM and SIGTERM -> SIGKILL waits
  std::vector<ProcessDescription> processes;
  std::vector<LaunchArgument> arguments;  // declared arguments with their resolved values

  /// Semantic checks shared by the parser and by programmatically built descriptions
  /// (names, uniqueness, ranges, non-empty argv). Throws LaunchFileError naming the field.
  void check() const;
};

/// Invalid launch file: unreadable, malformed YAML, or a field that fails validation.
/// what() is "<file>: <field path>: <problem>" (plus " (line L, column C)" when known), or
/// "<file>:<line>:<col>: malformed YAML: <problem>" for syntax errors (which have no field).
class LaunchFileError : public config::ConfigError {
 public:
  LaunchFileError(std::string file, std::string field, std::string problem, int line = 0,
                  int column = 0);

  const std::string& file() const { return file_; }
  const std::string& field() const { return field_; }  // e.g. "processes[1].restart"; may be ""
  const std::string& problem() const { return problem_; }
  int line() const { return line_; }      // 1-based; 0 when unknown
  int column() const { return column_; }  // 1-based; 0 when unknown

 private:
  std::string file_;
  std::string field_;
  std::string problem_;
  int line_;
  int column_;
};

/// Reads and validates a launch file. Relative params_file entries are resolved against the
/// launch file's folder. Throws LaunchFileError.
/// `arguments` are the command line's name:=value settings (see launch_arguments.h).
LaunchDescription parseLaunchFile(const std::string& path,
                                  const std::map<std::string, std::string>& arguments = {});

/// Parses launch YAML held in memory; `source` names it in messages and `base_dir` anchors
/// relative paths (empty = current directory). Throws LaunchFileError.
LaunchDescription parseLaunchYaml(const std::string& yaml, const std::string& source,
                                  const std::string& base_dir = "",
                                  const std::map<std::string, std::string>& arguments = {});

}  // namespace auv::bringup
