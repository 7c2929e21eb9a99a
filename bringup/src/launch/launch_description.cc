#include "launch_description.h"

#include <cmath>
#include <string>
#include <utility>

#include "launch_names.h"

namespace auv::bringup {
namespace {

using launch_names::isIdentifier;
using launch_names::isValidComponentName;
using launch_names::join;
using launch_names::processPath;

std::string formatError(const std::string& file, const std::string& field,
                        const std::string& problem, int line, int column) {
  // Without a field (syntax errors) the location goes first, compiler style.
  if (field.empty() && line > 0) {
    return file + ":" + std::to_string(line) + ":" + std::to_string(column) + ": " + problem;
  }
  std::string message = file + ": ";
  if (!field.empty()) message += field + ": ";
  message += problem;
  if (line > 0) {
    message += " (line " + std::to_string(line) + ", column " + std::to_string(column) + ")";
  }
  return message;
}

}  // namespace

const char* toString(RestartPolicy policy) {
  switch (policy) {
    case RestartPolicy::ON_FAILURE:
      return "on-failure";
    case RestartPolicy::ALWAYS:
      return "always";
    case RestartPolicy::NEVER:
      break;
  }
  return "never";
}

const char* toString(DdsVendor vendor) {
  switch (vendor) {
    case DdsVendor::CYCLONEDDS:
      return "cyclonedds";
    case DdsVendor::FASTDDS:
      return "fastdds";
    case DdsVendor::DEFAULT:
      break;
  }
  return "";
}

LaunchFileError::LaunchFileError(std::string file, std::string field, std::string problem, int line,
                                 int column)
    : config::ConfigError(formatError(file, field, problem, line, column)),
      file_(std::move(file)),
      field_(std::move(field)),
      problem_(std::move(problem)),
      line_(line),
      column_(column) {}

void LaunchDescription::check() const {
  const auto fail = [this](const std::string& field, const std::string& problem) {
    throw LaunchFileError(source, field, problem);
  };
  const auto checkEnvironment = [&](const std::map<std::string, std::string>& variables,
                                    const std::string& field) {
    for (const auto& entry : variables) {
      const std::string& name = entry.first;
      if (!isIdentifier(name)) {
        fail(join(field, name), "invalid environment variable name '" + name + "'");
      }
    }
  };
  if (!std::isfinite(shutdown_timeout) || shutdown_timeout < 0.0) {
    fail("shutdown_timeout",
         "expected a duration in seconds >= 0, got " + std::to_string(shutdown_timeout));
  }
  checkEnvironment(environment, "environment");
  if (processes.empty()) fail("processes", "expected at least one process");
  std::set<std::string> names;
  for (size_t i = 0; i < processes.size(); ++i) {
    const ProcessDescription& process = processes[i];
    const std::string path = processPath(i);
    if (!isIdentifier(process.name)) {
      fail(join(path, "name"),
           "invalid process name '" + process.name + "' (must match [A-Za-z_][A-Za-z0-9_]*)");
    }
    if (!names.insert(process.name).second) {
      fail(join(path, "name"), "duplicate process name '" + process.name + "'");
    }
    switch (process.kind) {
      case ProcessKind::COMMAND:
        if (process.command.empty() || process.command[0].empty()) {
          fail(join(path, "command"), "expected at least the program name");
        }
        if (!process.components.empty()) {
          fail(join(path, "components"), "not allowed on a 'command' process");
        }
        if (!process.params_file.empty()) {
          fail(join(path, "params_file"), "not allowed on a 'command' process");
        }
        break;
      case ProcessKind::COMPONENT:
      case ProcessKind::COMPOSITION: {
        const bool single = process.kind == ProcessKind::COMPONENT;
        if (single ? process.components.size() != 1 : process.components.empty()) {
          fail(join(path, single ? "component" : "components"),
               single ? "expected exactly one component" : "expected at least one component");
        }
        if (!process.command.empty()) fail(join(path, "command"), "not allowed with components");
        std::set<std::string> node_names;
        for (size_t j = 0; j < process.components.size(); ++j) {
          const ComponentDescription& entry = process.components[j];
          const std::string entry_path =
              single ? path : join(path, "components[" + std::to_string(j) + "]");
          if (!isValidComponentName(entry.component)) {
            fail(join(entry_path, "component"), "invalid component name '" + entry.component + "'");
          }
          if (!isIdentifier(entry.node_name)) {
            fail(join(entry_path, "name"), "invalid node name '" + entry.node_name + "'");
          }
          if (!node_names.insert(entry.node_name).second) {
            fail(join(entry_path, "name"), "duplicate node name '" + entry.node_name + "'");
          }
          if (entry.parameters && !entry.parameters.IsNull() && !entry.parameters.IsMap()) {
            fail(join(entry_path, "parameters"), "expected a mapping of parameter: value");
          }
        }
        break;
      }
    }
    checkEnvironment(process.environment, join(path, "environment"));
    if (process.max_restarts && *process.max_restarts < 0) {
      fail(join(path, "max_restarts"),
           "expected a non-negative integer, got " + std::to_string(*process.max_restarts));
    }
    if (!std::isfinite(process.restart_delay) || process.restart_delay < 0.0) {
      fail(join(path, "restart_delay"),
           "expected a duration in seconds >= 0, got " + std::to_string(process.restart_delay));
    }
  }
}

}  // namespace auv::bringup
