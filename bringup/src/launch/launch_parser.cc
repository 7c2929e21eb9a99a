// Reading a launch file: YAML -> LaunchDescription, every error with the field's path.
#include "launch_description.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <set>
#include <sstream>
#include <utility>

#include "auv/config/spelling.h"
#include "auv/config/yaml_scalars.h"
#include "launch_names.h"

namespace auv::bringup {
namespace {

namespace fs = std::filesystem;
using launch_names::isIdentifier;
using launch_names::isValidComponentName;
using launch_names::join;
using launch_names::processPath;

constexpr const char* kTopLevelKeys[] = {"environment", "shutdown_timeout", "processes"};
constexpr const char* kProcessKeys[] = {"name",    "component",    "components",    "command",
                                        "vendor",  "parameters",   "params_file",   "environment",
                                        "restart", "max_restarts", "restart_delay", "required",
                                        "enabled"};
constexpr const char* kComponentEntryKeys[] = {"component", "name", "parameters"};

// Frequent spellings from other launch systems, suggested when the key is unknown.
const std::map<std::string, std::string>& keyAliases() {
  static const std::map<std::string, std::string> aliases = {
      {"env", "environment"},
      {"params", "parameters"},
      {"param", "parameters"},
      {"cmd", "command"},
      {"args", "command"},
      {"argv", "command"},
      {"executable", "command"},
      {"respawn", "restart"},
      {"respawn_delay", "restart_delay"},
      {"dds", "vendor"},
      {"rmw", "vendor"},
      {"node_name", "name"},
      {"node", "component"},
      {"nodes", "components"},
      {"parameters_file", "params_file"},
      {"param_file", "params_file"},
      {"timeout", "shutdown_timeout"},
      {"sigterm_timeout", "shutdown_timeout"},
      {"on_exit", "required"},
      {"condition", "enabled"},
      {"if", "enabled"},
  };
  return aliases;
}

// Closest candidate to `word`, or "" when nothing is close enough to be a plausible typo.
std::string suggest(const std::string& word, const std::vector<std::string>& candidates) {
  std::string lowered = word;
  std::transform(lowered.begin(), lowered.end(), lowered.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  std::replace(lowered.begin(), lowered.end(), '-', '_');
  const auto alias = keyAliases().find(lowered);
  if (alias != keyAliases().end() &&
      std::find(candidates.begin(), candidates.end(), alias->second) != candidates.end()) {
    return alias->second;
  }
  std::string best;
  size_t best_distance = std::string::npos;
  for (const std::string& candidate : candidates) {
    std::string normalized = candidate;
    std::replace(normalized.begin(), normalized.end(), '-', '_');
    const size_t distance = config::editDistance(lowered, normalized);
    if (distance < best_distance) {
      best_distance = distance;
      best = candidate;
    }
  }
  const size_t allowed = std::max<size_t>(1, std::min<size_t>(3, word.size() / 3));
  return best_distance <= allowed ? best : "";
}

std::string joinList(const std::vector<std::string>& items) {
  std::string out = "[";
  for (size_t i = 0; i < items.size(); ++i) out += (i ? ", " : "") + items[i];
  return out + "]";
}

// Short description of a node for "got ..." messages.
std::string describe(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Scalar:
      return "'" + node.Scalar() + "'";
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Map:
      return "a mapping";
    default:
      return "an empty value";
  }
}

// Parses one launch document; every failure throws LaunchFileError with a field path.
class Parser {
 public:
  Parser(std::string source, std::string base_dir)
      : source_(std::move(source)), base_dir_(std::move(base_dir)) {}

  LaunchDescription parse(const YAML::Node& root) {
    LaunchDescription launch;
    launch.source = source_;
    launch.base_dir = base_dir_;
    if (!root.IsMap()) {
      fail("", "expected a mapping with a 'processes' list at top level, got " + describe(root),
           root);
    }
    checkKeys(root, "", kTopLevelKeys);
    if (const YAML::Node env = root["environment"]) {
      launch.environment = parseEnvironment(env, "environment");
    }
    if (const YAML::Node timeout = root["shutdown_timeout"]) {
      launch.shutdown_timeout = parseSeconds(timeout, "shutdown_timeout");
    }
    const YAML::Node processes = root["processes"];
    if (!processes) fail("processes", "missing required key", root);
    if (!processes.IsSequence()) {
      fail("processes", "expected a list of processes, got " + describe(processes), processes);
    }
    if (processes.size() == 0) fail("processes", "expected at least one process", processes);

    std::map<std::string, size_t> first_use;
    for (size_t i = 0; i < processes.size(); ++i) {
      // `enabled: false` (usually `enabled: $(arg x)`) leaves a process out of this launch.
      if (processes[i].IsMap() && processes[i]["enabled"] &&
          !parseBool(processes[i]["enabled"], join(processPath(i), "enabled"))) {
        continue;
      }
      ProcessDescription process = parseProcess(processes[i], processPath(i));
      const auto [it, inserted] = first_use.emplace(process.name, i);
      if (!inserted) {
        fail(join(processPath(i), "name"),
             "duplicate process name '" + process.name + "' (first used by " +
                 processPath(it->second) + ")",
             processes[i]["name"]);
      }
      launch.processes.push_back(std::move(process));
    }
    launch.check();
    return launch;
  }

 private:
  [[noreturn]] void fail(const std::string& field, const std::string& problem,
                         const YAML::Node& at) const {
    const YAML::Mark mark = at.IsDefined() ? at.Mark() : YAML::Mark::null_mark();
    failAt(field, problem, mark);
  }

  [[noreturn]] void failAt(const std::string& field, const std::string& problem,
                           const YAML::Mark& mark) const {
    const bool known = !mark.is_null() && mark.line >= 0;
    throw LaunchFileError(source_, field, problem, known ? mark.line + 1 : 0,
                          known ? mark.column + 1 : 0);
  }

  // Rejects non-scalar, duplicate and unknown keys (with a suggestion) in a mapping.
  template <size_t N>
  void checkKeys(const YAML::Node& map, const std::string& path, const char* const (&allowed)[N]) {
    const std::vector<std::string> keys(std::begin(allowed), std::end(allowed));
    std::set<std::string> seen;
    for (const auto& entry : map) {
      if (!entry.first.IsScalar()) {
        failAt(path.empty() ? "<top level>" : path, "keys must be plain names", entry.first.Mark());
      }
      const std::string& key = entry.first.Scalar();
      const std::string field = join(path, key);
      if (!seen.insert(key).second) failAt(field, "duplicate key", entry.first.Mark());
      if (std::find(keys.begin(), keys.end(), key) == keys.end()) {
        const std::string hint = suggest(key, keys);
        failAt(field,
               hint.empty() ? "unknown key; expected one of " + joinList(keys)
                            : "unknown key; did you mean '" + hint + "'?",
               entry.first.Mark());
      }
    }
  }

  std::string parseString(const YAML::Node& node, const std::string& field,
                          const std::string& what) const {
    if (!node.IsScalar()) fail(field, "expected " + what + ", got " + describe(node), node);
    return node.Scalar();
  }

  // Numbers and booleans by the one scalar rule of every reader (auv/config/yaml_scalars.h).
  double parseSeconds(const YAML::Node& node, const std::string& field) const {
    const std::optional<double> value =
        config::isPlainScalar(node) ? config::parseNumber(node.Scalar()) : std::nullopt;
    if (!value || !std::isfinite(*value) || *value < 0.0) {
      fail(field, "expected a duration in seconds >= 0, got " + describe(node), node);
    }
    return *value;
  }

  int parseCount(const YAML::Node& node, const std::string& field) const {
    const std::optional<int64_t> value =
        config::isPlainScalar(node) ? config::parseInteger(node.Scalar()) : std::nullopt;
    if (!value || *value < 0 || *value > std::numeric_limits<int>::max()) {
      fail(field, "expected a non-negative integer, got " + describe(node), node);
    }
    return static_cast<int>(*value);
  }

  // Strict YAML 1.2 core booleans, like every reader: yes/no/on/off/1/0 are errors.
  bool parseBool(const YAML::Node& node, const std::string& field) const {
    const std::optional<bool> value =
        config::isPlainScalar(node) ? config::parseBool(node.Scalar()) : std::nullopt;
    if (!value) fail(field, "expected true or false, got " + describe(node), node);
    return *value;
  }

  // Matches a scalar against the spellings of an enum; suggests the closest on a typo.
  template <typename Enum, size_t N>
  Enum parseChoice(const YAML::Node& node, const std::string& field,
                   const std::pair<const char*, Enum> (&choices)[N]) const {
    std::vector<std::string> names;
    for (const auto& choice : choices) names.emplace_back(choice.first);
    const std::string expected = "expected one of " + joinList(names);
    if (!node.IsScalar()) fail(field, expected + ", got " + describe(node), node);
    for (const auto& choice : choices) {
      if (node.Scalar() == choice.first) return choice.second;
    }
    const std::string hint = suggest(node.Scalar(), names);
    fail(field,
         expected + ", got " + describe(node) +
             (hint.empty() ? "" : "; did you mean '" + hint + "'?"),
         node);
  }

  std::map<std::string, std::string> parseEnvironment(const YAML::Node& node,
                                                      const std::string& field) {
    std::map<std::string, std::string> environment;
    if (node.IsNull()) return environment;
    if (!node.IsMap()) {
      fail(field, "expected a mapping of NAME: value, got " + describe(node), node);
    }
    std::set<std::string> seen;
    for (const auto& entry : node) {
      const std::string name = parseString(entry.first, field, "a variable name");
      const std::string entry_field = join(field, name);
      if (!isIdentifier(name)) {
        failAt(entry_field, "invalid environment variable name '" + name + "'", entry.first.Mark());
      }
      if (!seen.insert(name).second) failAt(entry_field, "duplicate key", entry.first.Mark());
      if (!entry.second.IsScalar()) {
        failAt(entry_field, "expected a string value, got " + describe(entry.second),
               entry.second.IsNull() ? entry.first.Mark() : entry.second.Mark());
      }
      environment[name] = entry.second.Scalar();
    }
    return environment;
  }

  // Inline parameters: a mapping of name -> scalar, list or nested mapping (namespace).
  YAML::Node parseParameters(const YAML::Node& node, const std::string& field) {
    if (node.IsNull()) return YAML::Node();
    if (!node.IsMap()) {
      fail(field, "expected a mapping of parameter: value, got " + describe(node), node);
    }
    checkParameterTree(node, field);
    return YAML::Clone(node);
  }

  void checkParameterTree(const YAML::Node& map, const std::string& field) {
    std::set<std::string> seen;
    for (const auto& entry : map) {
      if (!entry.first.IsScalar() || entry.first.Scalar().empty()) {
        failAt(field, "parameter names must be non-empty plain names", entry.first.Mark());
      }
      const std::string entry_field = join(field, entry.first.Scalar());
      if (!seen.insert(entry.first.Scalar()).second) {
        failAt(entry_field, "duplicate key", entry.first.Mark());
      }
      if (entry.second.IsNull()) failAt(entry_field, "missing value", entry.first.Mark());
      if (entry.second.IsMap()) checkParameterTree(entry.second, entry_field);
    }
  }

  std::vector<std::string> parseCommand(const YAML::Node& node, const std::string& field) {
    if (node.IsScalar()) {
      fail(field,
           "expected a list of arguments, e.g. [sh, -c, \"" + node.Scalar() + "\"], got " +
               describe(node),
           node);
    }
    if (!node.IsSequence()) {
      fail(field, "expected a list of arguments, got " + describe(node), node);
    }
    if (node.size() == 0) fail(field, "expected at least the program name", node);
    std::vector<std::string> argv;
    for (size_t i = 0; i < node.size(); ++i) {
      argv.push_back(
          parseString(node[i], field + "[" + std::to_string(i) + "]", "a string argument"));
    }
    if (argv[0].empty()) fail(field + "[0]", "program name is empty", node[0]);
    return argv;
  }

  std::string parseComponentName(const YAML::Node& node, const std::string& field) {
    const std::string component = parseString(node, field, "a component name");
    if (!isValidComponentName(component)) {
      fail(field,
           "invalid component name '" + component +
               "' (must be non-empty, not start with '-', without ':' or whitespace)",
           node);
    }
    return component;
  }

  ComponentDescription parseComponentEntry(const YAML::Node& node, const std::string& path) {
    if (!node.IsMap()) {
      fail(path,
           "expected a mapping {component: ..., name: ..., parameters: ...}, got " + describe(node),
           node);
    }
    checkKeys(node, path, kComponentEntryKeys);
    ComponentDescription entry;
    const YAML::Node component = node["component"];
    if (!component) fail(join(path, "component"), "missing required key", node);
    entry.component = parseComponentName(component, join(path, "component"));
    if (const YAML::Node name = node["name"]) {
      entry.node_name = parseString(name, join(path, "name"), "a node name");
      if (!isIdentifier(entry.node_name)) {
        fail(join(path, "name"),
             "invalid node name '" + entry.node_name + "' (must match [A-Za-z_][A-Za-z0-9_]*)",
             name);
      }
    } else {
      entry.node_name = entry.component;
      if (!isIdentifier(entry.node_name)) {
        fail(join(path, "name"),
             "missing; component '" + entry.component +
                 "' is not a valid node name, give one with 'name:'",
             node);
      }
    }
    if (const YAML::Node parameters = node["parameters"]) {
      entry.parameters = parseParameters(parameters, join(path, "parameters"));
    }
    return entry;
  }

  ProcessDescription parseProcess(const YAML::Node& node, const std::string& path) {
    if (!node.IsMap()) {
      fail(path, "expected a mapping describing a process, got " + describe(node), node);
    }
    checkKeys(node, path, kProcessKeys);
    ProcessDescription process;

    const YAML::Node name = node["name"];
    if (!name) fail(join(path, "name"), "missing required key", node);
    process.name = parseString(name, join(path, "name"), "a process name");
    if (!isIdentifier(process.name)) {
      fail(join(path, "name"),
           "invalid process name '" + process.name + "' (must match [A-Za-z_][A-Za-z0-9_]*)", name);
    }

    // Exactly one of component / components / command.
    std::vector<std::string> kinds;
    for (const char* key : {"component", "components", "command"}) {
      if (node[key]) kinds.emplace_back(key);
    }
    if (kinds.empty()) {
      fail(path, "expected exactly one of 'component', 'components' or 'command', got none", node);
    }
    if (kinds.size() > 1) {
      fail(join(path, kinds[1]),
           "expected exactly one of 'component', 'components' or 'command', got both '" + kinds[0] +
               "' and '" + kinds[1] + "'",
           node[kinds[1]]);
    }

    if (const YAML::Node component = node["component"]) {
      process.kind = ProcessKind::COMPONENT;
      ComponentDescription entry;
      entry.component = parseComponentName(component, join(path, "component"));
      entry.node_name = process.name;
      if (const YAML::Node parameters = node["parameters"]) {
        entry.parameters = parseParameters(parameters, join(path, "parameters"));
      }
      process.components.push_back(std::move(entry));
    } else if (const YAML::Node components = node["components"]) {
      process.kind = ProcessKind::COMPOSITION;
      const std::string field = join(path, "components");
      if (!components.IsSequence()) {
        fail(field, "expected a list of {component: ..., name: ...}, got " + describe(components),
             components);
      }
      if (components.size() == 0) fail(field, "expected at least one component", components);
      std::map<std::string, size_t> first_use;
      for (size_t i = 0; i < components.size(); ++i) {
        const std::string entry_path = field + "[" + std::to_string(i) + "]";
        ComponentDescription entry = parseComponentEntry(components[i], entry_path);
        const auto [it, inserted] = first_use.emplace(entry.node_name, i);
        if (!inserted) {
          fail(join(entry_path, "name"),
               "duplicate node name '" + entry.node_name + "' in this process (first used by " +
                   field + "[" + std::to_string(it->second) + "])",
               components[i]["name"] ? components[i]["name"] : components[i]);
        }
        process.components.push_back(std::move(entry));
      }
      if (const YAML::Node parameters = node["parameters"]) {
        fail(join(path, "parameters"),
             "not allowed on a composition; give parameters per entry in 'components'", parameters);
      }
    } else {
      process.kind = ProcessKind::COMMAND;
      process.command = parseCommand(node["command"], join(path, "command"));
      for (const char* key : {"parameters", "params_file"}) {
        if (const YAML::Node misplaced = node[key]) {
          fail(join(path, key),
               "not allowed on a 'command' process (only for 'component' or 'components')",
               misplaced);
        }
      }
    }

    if (const YAML::Node vendor = node["vendor"]) {
      static constexpr std::pair<const char*, DdsVendor> kVendors[] = {
          {"cyclonedds", DdsVendor::CYCLONEDDS}, {"fastdds", DdsVendor::FASTDDS}};
      process.vendor = parseChoice(vendor, join(path, "vendor"), kVendors);
    }
    if (const YAML::Node params_file = node["params_file"]) {
      const std::string field = join(path, "params_file");
      const std::string file = parseString(params_file, field, "a file path");
      if (file.empty()) fail(field, "expected a file path, got an empty string", params_file);
      fs::path resolved(file);
      if (resolved.is_relative()) resolved = fs::path(base_dir_) / resolved;
      resolved = resolved.lexically_normal();
      std::error_code error;
      if (!fs::is_regular_file(resolved, error)) {
        fail(field, "file not found: " + resolved.string(), params_file);
      }
      process.params_file = resolved.string();
    }
    if (const YAML::Node env = node["environment"]) {
      process.environment = parseEnvironment(env, join(path, "environment"));
    }
    if (const YAML::Node restart = node["restart"]) {
      static constexpr std::pair<const char*, RestartPolicy> kPolicies[] = {
          {"never", RestartPolicy::NEVER},
          {"on-failure", RestartPolicy::ON_FAILURE},
          {"always", RestartPolicy::ALWAYS}};
      process.restart = parseChoice(restart, join(path, "restart"), kPolicies);
    }
    if (const YAML::Node max_restarts = node["max_restarts"]) {
      process.max_restarts = parseCount(max_restarts, join(path, "max_restarts"));
    }
    if (const YAML::Node delay = node["restart_delay"]) {
      process.restart_delay = parseSeconds(delay, join(path, "restart_delay"));
    }
    if (const YAML::Node required = node["required"]) {
      process.required = parseBool(required, join(path, "required"));
    }
    return process;
  }

  std::string source_;
  std::string base_dir_;
};

}  // namespace

LaunchDescription parseLaunchYaml(const std::string& yaml, const std::string& source,
                                  const std::string& base_dir,
                                  const std::map<std::string, std::string>& arguments) {
  std::error_code error;
  fs::path base = base_dir.empty() ? fs::current_path(error) : fs::path(base_dir);
  if (base.is_relative()) base = fs::absolute(base, error);
  YAML::Node root;
  try {
    root = config::loadYaml(yaml);  // refuses aliases no walk ends on (yaml_scalars.h)
  } catch (const YAML::ParserException& e) {
    const bool known = !e.mark.is_null() && e.mark.line >= 0;
    throw LaunchFileError(source, "", "malformed YAML: " + e.msg, known ? e.mark.line + 1 : 0,
                          known ? e.mark.column + 1 : 0);
  } catch (const YAML::Exception& e) {
    throw LaunchFileError(source, "", std::string("cannot read YAML: ") + e.what());
  }
  if (!root.IsDefined() || root.IsNull()) {
    throw LaunchFileError(source, "",
                          "empty launch file; expected a mapping with a 'processes' list");
  }
  const std::vector<LaunchArgument> declared = applyLaunchArguments(root, arguments, source);
  LaunchDescription launch = Parser(source, base.lexically_normal().string()).parse(root);
  launch.arguments = declared;
  return launch;
}

LaunchDescription parseLaunchFile(const std::string& path,
                                  const std::map<std::string, std::string>& arguments) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw LaunchFileError(path, "", std::string("cannot open: ") + std::strerror(errno));
  std::ostringstream content;
  content << in.rdbuf();
  if (in.bad()) throw LaunchFileError(path, "", "read error");
  std::error_code error;
  const fs::path absolute = fs::absolute(fs::path(path), error);
  return parseLaunchYaml(content.str(), path, absolute.parent_path().string(), arguments);
}

}  // namespace auv::bringup
