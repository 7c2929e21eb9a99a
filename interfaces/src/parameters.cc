#include "auv/interfaces/parameters.h"

#include "auv/config/spelling.h"
#include "auv/config/yaml_scalars.h"

#include "parameter_conversion.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <system_error>

#include <yaml-cpp/yaml.h>

namespace auv::interfaces {

// ParameterType is the index of the ParameterValue alternative; check the two orders agree.
template <ParameterType kType>
using AlternativeOf = std::variant_alternative_t<static_cast<size_t>(kType), ParameterValue>;
static_assert(
    std::is_same_v<AlternativeOf<ParameterType::BOOL>, bool> &&
        std::is_same_v<AlternativeOf<ParameterType::INTEGER>, int64_t> &&
        std::is_same_v<AlternativeOf<ParameterType::DOUBLE>, double> &&
        std::is_same_v<AlternativeOf<ParameterType::STRING>, std::string> &&
        std::is_same_v<AlternativeOf<ParameterType::BOOL_ARRAY>, std::vector<bool>> &&
        std::is_same_v<AlternativeOf<ParameterType::INTEGER_ARRAY>, std::vector<int64_t>> &&
        std::is_same_v<AlternativeOf<ParameterType::DOUBLE_ARRAY>, std::vector<double>> &&
        std::is_same_v<AlternativeOf<ParameterType::STRING_ARRAY>, std::vector<std::string>>,
    "ParameterType must follow the order of the ParameterValue alternatives");

// Value conversion and constraint checks (parameter_conversion.h).
using config::describeNode;
using config::markText;
using detail::checkConstraints;
using detail::checkDescriptor;
using detail::coerce;
using detail::Conversion;
using detail::convertNode;
using detail::Declared;
using detail::expectedGot;
using detail::formatDouble;
using detail::formatList;
using detail::formatScalar;
using detail::integerBounds;
using detail::isInteger;
using detail::kInt64Max;
using detail::kInt64Min;
using detail::Violation;

namespace {

// Precedence levels of an override; higher wins, then later sequence number wins.
enum class Rank { WILDCARD = 0, NODE = 1, COMMAND_LINE = 2 };

// One value for one parameter name from one source.
struct Override {
  std::string name;    // dotted parameter name
  YAML::Node value;    // scalar, sequence or null
  std::string source;  // file path or kCommandLineSource
  Rank rank;           // wildcard, node-specific or command line
  uint64_t sequence;   // load order; later wins within a rank
  YAML::Mark mark;     // position of the key in the source (null for the command line)
};

std::string lastComponent(const std::string& name) {
  const size_t dot = name.rfind('.');
  return dot == std::string::npos ? name : name.substr(dot + 1);
}

// Closest declared name to `name`, if any is close enough to be a likely typo.
std::optional<std::string> closestName(const std::string& name,
                                       const std::vector<std::string>& declared) {
  const std::string best = config::closestMatch(name, declared);
  if (!best.empty()) return best;
  // Same leaf name under another prefix (e.g. "range" vs "planner.range").
  for (const auto& candidate : declared) {
    if (lastComponent(candidate) == lastComponent(name)) return candidate;
  }
  return std::nullopt;
}

std::string stripLeadingSlash(const std::string& name) {
  return !name.empty() && name[0] == '/' ? name.substr(1) : name;
}

std::string trim(const std::string& text) {
  const size_t begin = text.find_first_not_of(" \t");
  if (begin == std::string::npos) return "";
  const size_t end = text.find_last_not_of(" \t");
  return text.substr(begin, end - begin + 1);
}

std::string nodeKindText(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Scalar:
      return "a scalar";
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Map:
      return "a map";
    default:
      return "null";
  }
}

// Where each parameter of one file is set first, by rank and name (an index into the overrides).
using FirstSet = std::map<std::pair<Rank, std::string>, size_t>;

// Appends the leaves of map `node` as overrides, with nested keys joined by '.'.
void flatten(const YAML::Node& node, const std::string& prefix, const std::string& source,
             Rank rank, std::vector<Override>* out, FirstSet* first) {
  for (const auto& entry : node) {
    const YAML::Node& key = entry.first;
    if (!key.IsScalar() || key.Scalar().empty()) {
      throw ParameterError(source + markText(key.Mark()) +
                           ": parameter names must be non-empty scalars");
    }
    const std::string name = prefix.empty() ? key.Scalar() : prefix + "." + key.Scalar();
    const YAML::Node& value = entry.second;
    if (value.IsMap()) {
      flatten(value, name, source, rank, out, first);
    } else {
      // A map, not a scan of the overrides so far: aliases can make a file of a few lines set
      // tens of thousands of parameters.
      const auto [previous, inserted] = first->emplace(std::make_pair(rank, name), out->size());
      if (!inserted) {
        throw ParameterError(source + markText(key.Mark()) + ": parameter '" + name +
                             "' is set twice for the same node (first at line " +
                             std::to_string((*out)[previous->second].mark.line + 1) + ")");
      }
      out->push_back(Override{name, value, source, rank, 0, key.Mark()});
    }
  }
}

void emitValue(YAML::Emitter& out, const ParameterValue& value) {
  std::visit(
      [&](const auto& v) {
        using V = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<V, bool>) {
          out << v;
        } else if constexpr (std::is_same_v<V, int64_t>) {
          out << static_cast<long long>(v);
        } else if constexpr (std::is_same_v<V, double>) {
          out << formatDouble(v);
        } else if constexpr (std::is_same_v<V, std::string>) {
          out << YAML::DoubleQuoted << v;
        } else {
          out << YAML::Flow << YAML::BeginSeq;
          for (size_t i = 0; i < v.size(); ++i) {
            emitValue(out, ParameterValue(typename V::value_type(v[i])));
          }
          out << YAML::EndSeq;
        }
      },
      value);
}

}  // namespace

// ---------------------------------------------------------------------------------------------

std::string toString(ParameterType type) {
  switch (type) {
    case ParameterType::BOOL:
      return "bool";
    case ParameterType::INTEGER:
      return "integer";
    case ParameterType::DOUBLE:
      return "double";
    case ParameterType::STRING:
      return "string";
    case ParameterType::BOOL_ARRAY:
      return "bool_array";
    case ParameterType::INTEGER_ARRAY:
      return "integer_array";
    case ParameterType::DOUBLE_ARRAY:
      return "double_array";
    case ParameterType::STRING_ARRAY:
      return "string_array";
  }
  return "unknown";
}

std::string toString(const ParameterValue& value) {
  return std::visit(
      [](const auto& v) -> std::string {
        using V = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<V, std::vector<bool>> ||
                      std::is_same_v<V, std::vector<int64_t>> ||
                      std::is_same_v<V, std::vector<double>> ||
                      std::is_same_v<V, std::vector<std::string>>) {
          return formatList(v);
        } else {
          return formatScalar<V>(v);
        }
      },
      value);
}

namespace detail {

void throwDoesNotFit(const std::string& name, const std::string& value, int64_t min, int64_t max) {
  throw ParameterError("parameter '" + name + "': value " + value +
                       " does not fit in the requested type [" + std::to_string(min) + ", " +
                       std::to_string(max) + "]");
}

void throwWrongType(const std::string& name, ParameterType declared, ParameterType requested) {
  throw ParameterError("parameter '" + name + "' is declared as " + toString(declared) +
                       ", requested as " + toString(requested));
}

}  // namespace detail

struct Parameters::Impl {
  std::string node_name;     // selects file sections
  mutable std::mutex mutex;  // guards everything below
  std::mutex set_mutex;      // serializes set() across its unlocked callback phase
  std::map<std::string, Declared> declared;
  std::vector<std::string> order;   // declaration order
  std::vector<Override> overrides;  // in load order
  std::vector<Callback> callbacks;  // onSet hooks
  uint64_t next_sequence = 0;

  // Throws if an override arrives for an already declared parameter (it could not apply).
  void checkNotDeclared(const std::vector<Override>& incoming) const {
    for (const auto& o : incoming) {
      if (declared.count(o.name) > 0) {
        throw ParameterError("parameter '" + o.name + "' in " + o.source +
                             ": already declared; load parameter files and overrides before "
                             "declaring parameters (use set() to change values at runtime)");
      }
    }
  }

  void append(std::vector<Override> incoming) {
    for (auto& o : incoming) {
      o.sequence = next_sequence++;
      overrides.push_back(std::move(o));
    }
  }

  // Highest-precedence override for `name`, or nullptr.
  const Override* bestOverride(const std::string& name) const {
    const Override* best = nullptr;
    for (const auto& o : overrides) {
      if (o.name != name) continue;
      if (best == nullptr ||
          std::make_pair(o.rank, o.sequence) > std::make_pair(best->rank, best->sequence)) {
        best = &o;
      }
    }
    return best;
  }

  const Declared& find(const std::string& name) const {
    const auto it = declared.find(name);
    if (it == declared.end()) {
      throw ParameterError("parameter '" + name + "' of node '" + node_name + "' is not declared");
    }
    return it->second;
  }
};

Parameters::Parameters(std::string node_name) : impl_(std::make_unique<Impl>()) {
  impl_->node_name = std::move(node_name);
}

Parameters::~Parameters() = default;

void Parameters::loadFile(const std::string& path) {
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) {
    throw ParameterError(path + ": cannot read parameter file: is a directory");
  }
  std::ifstream file(path, std::ios::binary);
  if (!file) {
    throw ParameterError(path + ": cannot read parameter file: " + std::strerror(errno));
  }
  std::ostringstream text;
  text << file.rdbuf();
  if (file.bad()) {
    throw ParameterError(path + ": cannot read parameter file: " + std::strerror(errno));
  }
  loadYaml(text.str(), path);
}

void Parameters::loadYaml(const std::string& text, const std::string& source_name) {
  YAML::Node root;
  try {
    root = config::loadYaml(text);
  } catch (const YAML::Exception& e) {
    throw ParameterError(source_name + markText(e.mark) + ": malformed YAML: " + e.msg);
  }
  if (root.IsNull()) return;  // empty file
  if (!root.IsMap()) {
    throw ParameterError(source_name + markText(root.Mark()) +
                         ": expected a map of node names at the top level, got " +
                         nodeKindText(root));
  }
  const std::string own_name = stripLeadingSlash(impl_->node_name);
  std::vector<Override> incoming;
  FirstSet first;
  for (const auto& section : root) {
    const YAML::Node& key = section.first;
    if (!key.IsScalar()) {
      throw ParameterError(source_name + markText(key.Mark()) +
                           ": node names at the top level must be scalars");
    }
    Rank rank;
    if (key.Scalar() == "/**" || key.Scalar() == "*") {
      rank = Rank::WILDCARD;
    } else if (stripLeadingSlash(key.Scalar()) == own_name) {
      rank = Rank::NODE;
    } else {
      continue;  // another node's section
    }
    const YAML::Node& section_value = section.second;
    if (section_value.IsNull()) continue;
    if (!section_value.IsMap()) {
      throw ParameterError(source_name + markText(section_value.Mark()) + ": section '" +
                           key.Scalar() + "' must be a map of parameters, got " +
                           nodeKindText(section_value));
    }
    // Accept ROS 2 files: "node: {ros__parameters: {...}}".
    const YAML::Node ros_parameters =
        section_value.size() == 1 ? section_value["ros__parameters"] : YAML::Node();
    const bool ros_file = ros_parameters && ros_parameters.IsMap();
    const YAML::Node parameters = ros_file ? ros_parameters : section_value;
    flatten(parameters, "", source_name, rank, &incoming, &first);
  }
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->checkNotDeclared(incoming);
  impl_->append(std::move(incoming));
}

void Parameters::setOverride(const std::string& assignment, const std::string& source_name) {
  const size_t separator = assignment.find(":=");
  const std::string name =
      separator == std::string::npos ? "" : trim(assignment.substr(0, separator));
  if (name.empty()) {
    throw ParameterError(source_name + ": expected 'name:=value', got '" + assignment + "'");
  }
  YAML::Node value;
  try {
    value = config::loadYaml(assignment.substr(separator + 2));
  } catch (const YAML::Exception& e) {
    throw ParameterError(source_name + ": malformed value for parameter '" + name + "': " + e.msg);
  }
  if (value.IsMap()) {
    throw ParameterError(source_name + ": value for parameter '" + name +
                         "' must be a scalar or a list, got a map");
  }
  std::vector<Override> incoming{
      Override{name, value, source_name, Rank::COMMAND_LINE, 0, YAML::Mark::null_mark()}};
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->checkNotDeclared(incoming);
  impl_->append(std::move(incoming));
}

std::string Parameters::declare(const std::string& name, const char* default_value,
                                const ParameterDescriptor& descriptor) {
  return declare<std::string>(name, std::string(default_value), descriptor);
}

ParameterValue Parameters::declareValue(const std::string& name, ParameterValue default_value,
                                        const ParameterDescriptor& descriptor, int64_t int_min,
                                        int64_t int_max) {
  if (name.empty() || name.front() == '.' || name.back() == '.' ||
      name.find("..") != std::string::npos) {
    throw ParameterError("invalid parameter name '" + name + "'");
  }
  const ParameterType type = typeOf(default_value);
  std::lock_guard<std::mutex> lock(impl_->mutex);
  if (const auto it = impl_->declared.find(name); it != impl_->declared.end()) {
    const ParameterType existing = typeOf(it->second.value);
    if (existing != type) {
      throw ParameterError("parameter '" + name + "' is already declared as " + toString(existing) +
                           ", cannot redeclare it as " + toString(type));
    }
    return it->second.value;
  }
  Declared declared{std::move(default_value), descriptor, int_min, int_max, "default"};
  checkDescriptor(name, declared);
  if (const auto violation = checkConstraints(declared, declared.value)) {
    throw ParameterError("parameter '" + name + "': invalid default: " +
                         expectedGot(declared, "'" + toString(declared.value) + "'", *violation));
  }
  if (const Override* o = impl_->bestOverride(name)) {
    const Conversion conversion = convertNode(o->value, type);
    std::optional<Violation> violation;
    if (!conversion.value) {
      violation = conversion.violation;
    } else {
      violation = checkConstraints(declared, *conversion.value);
    }
    if (violation) {
      throw ParameterError("parameter '" + name + "' in " + o->source + ": " +
                           expectedGot(declared, describeNode(o->value), *violation));
    }
    declared.value = *conversion.value;
    declared.source = o->source;
  }
  ParameterValue value = declared.value;
  impl_->declared.emplace(name, std::move(declared));
  impl_->order.push_back(name);
  return value;
}

ParameterValue Parameters::getValue(const std::string& name) const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->find(name).value;
}

ParameterType Parameters::type(const std::string& name) const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return typeOf(impl_->find(name).value);
}

bool Parameters::has(const std::string& name) const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->declared.count(name) > 0;
}

std::vector<std::string> Parameters::names() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->order;
}

Parameters::SetResult Parameters::set(const std::string& name, const ParameterValue& value) {
  std::lock_guard<std::mutex> set_lock(impl_->set_mutex);
  Declared declared;
  std::vector<Callback> callbacks;
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    const auto it = impl_->declared.find(name);
    if (it == impl_->declared.end()) {
      return {false, "parameter '" + name + "' of node '" + impl_->node_name +
                         "' is not declared; cannot set it to '" + toString(value) + "'"};
    }
    declared = it->second;
    callbacks = impl_->callbacks;
  }
  const ParameterType type = typeOf(declared.value);
  if (declared.descriptor.read_only) {
    return {false,
            "parameter '" + name + "' is read-only; cannot set it to '" + toString(value) + "'"};
  }
  const ParameterValue normalized = coerce(value, type);
  if (typeOf(normalized) != type) {
    return {false, "parameter '" + name + "': " +
                       expectedGot(declared, toString(typeOf(value)) + " '" + toString(value) + "'",
                                   Violation{})};
  }
  if (const auto violation = checkConstraints(declared, normalized)) {
    return {false, "parameter '" + name +
                       "': " + expectedGot(declared, "'" + toString(normalized) + "'", *violation)};
  }
  for (const auto& callback : callbacks) {
    SetResult result;
    try {
      result = callback(name, normalized);
    } catch (const std::exception& e) {
      result = {false, std::string("callback threw: ") + e.what()};
    }
    if (!result.ok) {
      return {false, "parameter '" + name + "' = '" + toString(normalized) +
                         "' rejected: " + result.reason};
    }
  }
  std::lock_guard<std::mutex> lock(impl_->mutex);
  Declared& stored = impl_->declared.at(name);
  stored.value = normalized;
  stored.source = "set()";
  return {true, ""};
}

Parameters::SetResult Parameters::set(const std::string& name, const char* value) {
  return set(name, ParameterValue(std::string(value)));
}

Parameters::SetResult Parameters::setFromYaml(const std::string& name,
                                              const std::string& yaml_value) {
  Declared declared;
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    const auto it = impl_->declared.find(name);
    if (it == impl_->declared.end()) {
      return {false, "parameter '" + name + "' of node '" + impl_->node_name +
                         "' is not declared; cannot set it to '" + yaml_value + "'"};
    }
    declared = it->second;
  }
  YAML::Node node;
  try {
    node = config::loadYaml(yaml_value);
  } catch (const YAML::Exception& e) {
    return {false, "parameter '" + name + "': malformed value '" + yaml_value + "': " + e.msg};
  }
  const Conversion conversion = convertNode(node, typeOf(declared.value));
  if (!conversion.value) {
    return {false, "parameter '" + name +
                       "': " + expectedGot(declared, describeNode(node), conversion.violation)};
  }
  return set(name, *conversion.value);
}

void Parameters::onSet(Callback callback) {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->callbacks.push_back(std::move(callback));
}

std::vector<std::string> Parameters::unusedOverrides() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  std::vector<std::string> unused;
  std::set<std::string> reported;  // not a scan of `unused`: there may be tens of thousands
  for (const auto& o : impl_->overrides) {
    if (o.rank == Rank::WILDCARD || impl_->declared.count(o.name) > 0) continue;
    std::string text = "'" + o.name + "' from " + o.source;
    if (const auto suggestion = closestName(o.name, impl_->order)) {
      text += " (did you mean '" + *suggestion + "'?)";
    }
    if (reported.insert(text).second) unused.push_back(text);
  }
  return unused;
}

std::string Parameters::describe() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  YAML::Emitter out;
  out << YAML::BeginMap;
  for (const auto& name : impl_->order) {
    const Declared& declared = impl_->declared.at(name);
    const ParameterType type = typeOf(declared.value);
    const auto& d = declared.descriptor;
    out << YAML::Key << name << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "type" << YAML::Value << toString(type);
    out << YAML::Key << "value" << YAML::Value;
    emitValue(out, declared.value);
    if (!d.unit.empty()) out << YAML::Key << "unit" << YAML::Value << d.unit;
    if (isInteger(type)) {
      const auto [low, high] = integerBounds(declared);
      if (low != kInt64Min) out << YAML::Key << "min" << YAML::Value << static_cast<long long>(low);
      if (high != kInt64Max) {
        out << YAML::Key << "max" << YAML::Value << static_cast<long long>(high);
      }
    } else {
      if (d.min) out << YAML::Key << "min" << YAML::Value << formatDouble(*d.min);
      if (d.min && d.min_exclusive) out << YAML::Key << "min_exclusive" << YAML::Value << true;
      if (d.max) out << YAML::Key << "max" << YAML::Value << formatDouble(*d.max);
      if (d.max && d.max_exclusive) out << YAML::Key << "max_exclusive" << YAML::Value << true;
    }
    if (!d.choices.empty()) {
      out << YAML::Key << "choices" << YAML::Value << YAML::Flow << YAML::BeginSeq;
      for (const auto& choice : d.choices) out << choice;
      out << YAML::EndSeq;
    }
    if (d.read_only) out << YAML::Key << "read_only" << YAML::Value << true;
    if (!d.description.empty()) {
      out << YAML::Key << "description" << YAML::Value << d.description;
    }
    out << YAML::Key << "source" << YAML::Value << declared.source;
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

std::string Parameters::node_name() const { return impl_->node_name; }

}  // namespace auv::interfaces
