#include "process_command.h"

#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <stdexcept>

namespace auv::bringup {
namespace {

constexpr const char* kAuvProgram = "auv";  // argv[0] meaning "this auv executable"
constexpr const char* kDefaultPath = "/usr/local/bin:/usr/bin:/bin";

// Emits `node` keeping explicitly quoted or tagged scalars as strings (yaml-cpp's own node
// emitter would turn '123' into the integer 123).
void emitNode(YAML::Emitter& out, const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Scalar:
      if (node.Tag() != "?") out << YAML::DoubleQuoted;
      out << node.Scalar();
      break;
    case YAML::NodeType::Sequence:
      out << YAML::Flow << YAML::BeginSeq;
      for (const YAML::Node& item : node) emitNode(out, item);
      out << YAML::EndSeq;
      break;
    case YAML::NodeType::Map:
      out << YAML::BeginMap;
      for (const auto& entry : node) {
        out << YAML::Key << entry.first.Scalar() << YAML::Value;
        emitNode(out, entry.second);
      }
      out << YAML::EndMap;
      break;
    default:
      out << YAML::Null;
      break;
  }
}

bool hasParameters(const ComponentDescription& entry) {
  return entry.parameters && entry.parameters.IsMap() && entry.parameters.size() > 0;
}

}  // namespace

std::string inlineParametersYaml(const ProcessDescription& process) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  bool any = false;
  for (const ComponentDescription& entry : process.components) {
    if (!hasParameters(entry)) continue;
    any = true;
    out << YAML::Key << entry.node_name << YAML::Value;
    emitNode(out, entry.parameters);
  }
  out << YAML::EndMap;
  return any ? std::string(out.c_str()) + "\n" : "";
}

ProcessCommand buildProcessCommand(const LaunchDescription& launch,
                                   const ProcessDescription& process,
                                   const std::string& auv_executable,
                                   const std::string& inline_params_dir) {
  ProcessCommand command;
  const auto needAuv = [&]() -> const std::string& {
    if (auv_executable.empty()) {
      throw std::invalid_argument("process '" + process.name +
                                  "' needs the auv executable, but its path is empty");
    }
    return auv_executable;
  };
  if (process.kind == ProcessKind::COMMAND) {
    command.argv = process.command;
    if (!command.argv.empty() && command.argv[0] == kAuvProgram) command.argv[0] = needAuv();
  } else {
    command.argv = {needAuv(), "run"};
    for (const ComponentDescription& entry : process.components) {
      command.argv.push_back(entry.component + ":" + entry.node_name);
    }
    if (!process.params_file.empty()) {
      command.argv.insert(command.argv.end(), {"--params", process.params_file});
    }
    command.inline_params_yaml = inlineParametersYaml(process);
    if (!command.inline_params_yaml.empty()) {
      command.inline_params_path =
          (std::filesystem::path(inline_params_dir) / (process.name + ".params.yaml")).string();
      command.argv.insert(command.argv.end(), {"--params", command.inline_params_path});
    }
  }
  command.environment = launch.environment;
  for (const auto& [name, value] : process.environment) command.environment[name] = value;
  if (process.vendor != DdsVendor::DEFAULT) {
    command.environment["AUV_DDS"] = toString(process.vendor);
  }
  return command;
}

std::vector<std::string> mergeEnvironment(const char* const* base,
                                          const std::map<std::string, std::string>& overrides) {
  std::map<std::string, std::string> merged;
  for (const char* const* entry = base; entry != nullptr && *entry != nullptr; ++entry) {
    const char* equals = std::strchr(*entry, '=');
    if (equals == nullptr) continue;
    merged.emplace(std::string(*entry, equals), std::string(equals + 1));
  }
  for (const auto& [name, value] : overrides) merged[name] = value;
  std::vector<std::string> result;
  result.reserve(merged.size());
  for (const auto& [name, value] : merged) result.push_back(name + "=" + value);
  return result;
}

std::string findExecutable(const std::string& program, const std::string& path_variable) {
  if (program.find('/') != std::string::npos) return program;
  const std::string path = path_variable.empty() ? kDefaultPath : path_variable;
  size_t begin = 0;
  while (begin <= path.size()) {
    size_t end = path.find(':', begin);
    if (end == std::string::npos) end = path.size();
    const std::string dir = end > begin ? path.substr(begin, end - begin) : ".";
    const std::string candidate = dir + "/" + program;
    std::error_code error;
    if (access(candidate.c_str(), X_OK) == 0 && !std::filesystem::is_directory(candidate, error)) {
      return candidate;
    }
    begin = end + 1;
  }
  return "";
}

std::string shellQuote(const std::string& arg) {
  const bool plain = !arg.empty() && std::all_of(arg.begin(), arg.end(), [](unsigned char c) {
    return std::isalnum(c) || (c != '\0' && std::strchr("@%_+=:,./-", c) != nullptr);
  });
  if (plain) return arg;
  std::string quoted = "'";
  for (char c : arg) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

std::string formatCommand(const std::vector<std::string>& argv) {
  std::string out;
  for (size_t i = 0; i < argv.size(); ++i) out += (i ? " " : "") + shellQuote(argv[i]);
  return out;
}

}  // namespace auv::bringup
