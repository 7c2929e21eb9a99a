#include "auv/recon/common/option_set.h"

#include <yaml-cpp/yaml.h>

#include "auv/config/yaml_scalars.h"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace auv::recon {

namespace {

std::string flagName(const std::string& name) {
  std::string flag = name;
  std::replace(flag.begin(), flag.end(), '_', '-');
  return "--" + flag;
}

std::string canonical(std::string name) {
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
}

[[noreturn]] void bad(const std::string& where, const std::string& got, const char* expected) {
  throw std::invalid_argument(where + ": expected " + expected + ", got " + got);
}

// A flag's text or a YAML scalar to T by the one scalar rule of every reader (YAML 1.2 core
// schema, auv/config/yaml_scalars.h: `yes`, `1_000` and `0x1p3` are not values); `got` is the
// value as messages show it.
template <class T>
T parseValue(const std::string& where, const std::string& text, const std::string& got);

template <>
double parseValue<double>(const std::string& where, const std::string& text,
                          const std::string& got) {
  const std::optional<double> v = config::parseNumber(text);
  if (!v || !std::isfinite(*v)) bad(where, got, "a number");
  return *v;
}
template <>
float parseValue<float>(const std::string& where, const std::string& text, const std::string& got) {
  return static_cast<float>(parseValue<double>(where, text, got));
}
template <>
int64_t parseValue<int64_t>(const std::string& where, const std::string& text,
                            const std::string& got) {
  const std::optional<int64_t> v = config::parseInteger(text);
  if (!v) bad(where, got, "an integer");
  return *v;
}
template <>
int parseValue<int>(const std::string& where, const std::string& text, const std::string& got) {
  const int64_t v = parseValue<int64_t>(where, text, got);
  if (v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max()) {
    bad(where, got, "an integer in the int range");
  }
  return static_cast<int>(v);
}
template <>
uint64_t parseValue<uint64_t>(const std::string& where, const std::string& text,
                              const std::string& got) {
  const int64_t v = parseValue<int64_t>(where, text, got);
  if (v < 0) bad(where, got, "a non-negative integer");
  return static_cast<uint64_t>(v);
}
template <>
unsigned parseValue<unsigned>(const std::string& where, const std::string& text,
                              const std::string& got) {
  const uint64_t v = parseValue<uint64_t>(where, text, got);
  if (v > std::numeric_limits<unsigned>::max()) bad(where, got, "a smaller integer");
  return static_cast<unsigned>(v);
}
template <>
bool parseValue<bool>(const std::string& where, const std::string& text, const std::string& got) {
  const std::optional<bool> v = config::parseBool(text);
  if (!v) bad(where, got, "a boolean (true or false)");
  return *v;
}
template <>
std::string parseValue<std::string>(const std::string&, const std::string& text,
                                    const std::string&) {
  return text;
}

/// A flag's value as messages show it: 'fast'.
std::string flagText(const std::string& text) { return "'" + text + "'"; }

/// A YAML value to T: numbers and booleans must be plain scalars (a quoted "5" is a string).
template <class T>
T yamlValue(const YAML::Node& node, const std::string& where) {
  if (!node.IsScalar())
    throw std::invalid_argument(where + ": expected a single value, got " +
                                config::describeNode(node));
  if constexpr (!std::is_same_v<T, std::string>) {
    if (!config::isPlainScalar(node)) {
      return parseValue<T>(where, "", config::describeNode(node));  // refused, named as quoted
    }
  }
  return parseValue<T>(where, node.Scalar(), config::describeNode(node));
}

template <class T>
std::string showDefault(const T& value) {
  std::ostringstream out;
  if constexpr (std::is_same_v<T, bool>) {
    out << (value ? "true" : "false");
  } else {
    out << value;
  }
  return out.str();
}

template <class T>
const char* typeName() {
  if constexpr (std::is_same_v<T, bool>) return "bool";
  if constexpr (std::is_floating_point_v<T>) return "number";
  if constexpr (std::is_integral_v<T>) return "integer";
  return "text";
}

}  // namespace

OptionSet::OptionSet(std::string section) : section_(std::move(section)) {}

template <class T>
void OptionSet::add(const std::string& name, T* value, const std::string& help) {
  Entry e;
  e.name = name;
  e.help = help;
  if constexpr (std::is_same_v<T, std::vector<std::string>>) {
    e.repeatable = true;
    e.type = "text, repeatable";
    e.default_text = value->empty() ? "none" : "";
    for (const auto& v : *value) e.default_text += (e.default_text.empty() ? "" : ",") + v;
    auto cleared = std::make_shared<bool>(false);
    e.set = [value, cleared](const std::string& text) {
      if (!*cleared) value->clear();  // given values replace the default list
      *cleared = true;
      value->push_back(text);
    };
    e.set_yaml = [value](const YAML::Node& node, const std::string& where) {
      value->clear();
      if (node.IsSequence()) {
        for (const auto& item : node) value->push_back(yamlValue<std::string>(item, where));
      } else {
        value->push_back(yamlValue<std::string>(node, where));
      }
    };
  } else {
    using Parsed = T;
    e.type = typeName<T>();
    e.default_text = showDefault(*value);
    e.is_flag = std::is_same_v<T, bool>;
    e.set = [value, name](const std::string& text) {
      *value = static_cast<T>(parseValue<Parsed>(flagName(name), text, flagText(text)));
    };
    e.set_yaml = [value](const YAML::Node& node, const std::string& where) {
      *value = static_cast<T>(yamlValue<Parsed>(node, where));
    };
  }
  entries_.push_back(std::move(e));
}

template void OptionSet::add(const std::string&, double*, const std::string&);
template void OptionSet::add(const std::string&, float*, const std::string&);
template void OptionSet::add(const std::string&, int*, const std::string&);
template void OptionSet::add(const std::string&, unsigned*, const std::string&);
template void OptionSet::add(const std::string&, size_t*, const std::string&);
template void OptionSet::add(const std::string&, int64_t*, const std::string&);
template void OptionSet::add(const std::string&, bool*, const std::string&);
template void OptionSet::add(const std::string&, std::string*, const std::string&);
template void OptionSet::add(const std::string&, std::vector<std::string>*, const std::string&);

bool OptionSet::has(const std::string& name) const {
  return std::any_of(entries_.begin(), entries_.end(),
                     [&](const Entry& e) { return e.name == name; });
}

void OptionSet::positional(const std::string& name, std::string* value, const std::string& help,
                           bool required) {
  positionals_.push_back({name, help, value, required});
}

OptionSet::Entry* OptionSet::find(const std::string& name) {
  const std::string key = canonical(name);
  for (auto& e : entries_) {
    if (e.name == key) return &e;
  }
  return nullptr;
}

bool OptionSet::parse(const std::vector<std::string>& args) {
  for (size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--help" || args[i] == "-h") {
      std::cout << help();
      return false;
    }
    if (args[i] == "--config" || args[i].rfind("--config=", 0) == 0) {
      std::string file;
      if (args[i] == "--config") {
        if (i + 1 >= args.size()) throw std::invalid_argument("--config: missing file");
        file = args[++i];
      } else {
        file = args[i].substr(9);
      }
      applyConfigFile(file);
    }
  }
  size_t next_positional = 0;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    if (arg == "--config") {
      ++i;
      continue;
    }
    if (arg.rfind("--config=", 0) == 0) continue;
    if (arg.size() > 2 && arg.compare(0, 2, "--") == 0) {
      std::string name = arg.substr(2), text;
      bool has_text = false;
      if (const size_t eq = name.find('='); eq != std::string::npos) {
        text = name.substr(eq + 1);
        name = name.substr(0, eq);
        has_text = true;
      }
      Entry* e = find(name);
      if (e == nullptr && name.rfind("no-", 0) == 0 && !has_text) {
        Entry* negated = find(name.substr(3));
        if (negated != nullptr && negated->is_flag) {
          negated->set("false");
          continue;
        }
      }
      if (e == nullptr) {
        throw std::invalid_argument("--" + name + ": unknown option (`--help` lists them)");
      }
      if (!has_text) {
        if (e->is_flag) {
          text = "true";
        } else {
          if (i + 1 >= args.size())
            throw std::invalid_argument(flagName(e->name) + ": missing value");
          text = args[++i];
        }
      }
      e->set(text);
      continue;
    }
    if (next_positional >= positionals_.size()) {
      throw std::invalid_argument("unexpected argument '" + arg + "'");
    }
    *positionals_[next_positional++].value = arg;
  }
  for (size_t p = next_positional; p < positionals_.size(); ++p) {
    if (positionals_[p].required) {
      throw std::invalid_argument("missing <" + positionals_[p].name + ">");
    }
  }
  return true;
}

void OptionSet::applyConfigFile(const std::filesystem::path& file) {
  // OptionSet's errors are std::invalid_argument (exit code 2, like config::ConfigError).
  const config::YamlSection root = [&] {
    try {
      // The shared strict loader ("<file>:<line>:<column>: malformed YAML: ..."); an empty
      // file sets nothing.
      return config::loadYamlFile(file.string(), true);
    } catch (const config::ConfigError& e) {
      throw std::invalid_argument(std::string("--config: ") + e.what());
    }
  }();
  try {
    applyYaml(root.child(section_));
  } catch (const config::ConfigError& e) {
    throw std::invalid_argument(e.what());
  }
}

void OptionSet::applyYaml(const config::YamlSection& section) {
  std::vector<std::string> names;
  for (const auto& entry : entries_) names.push_back(entry.name);
  if (!section.node().IsMap()) return;  // absent or empty section: nothing
  for (const auto& item : section.node()) {
    const std::string key = item.first.IsScalar() ? item.first.Scalar() : "";
    Entry* e = find(key);  // either spelling: min_motion_px or min-motion-px
    if (e == nullptr) section.unknownKey(key, names);
    e->set_yaml(item.second, section.where(key));
  }
}

std::string OptionSet::help() const {
  std::ostringstream out;
  if (!positionals_.empty()) {
    out << "arguments:\n";
    for (const auto& p : positionals_) {
      out << "  <" << p.name << ">" << (p.required ? "" : " (optional)") << "  " << p.help << "\n";
    }
  }
  out << "options (also as `" << section_ << ":` keys of a --config YAML file):\n";
  for (const auto& e : entries_) {
    out << "  " << flagName(e.name) << (e.is_flag ? "" : " <" + e.type + ">") << "\n      "
        << e.help << " (default " << e.default_text << ")\n";
  }
  out << "  --config <file.yaml>\n      options from the file's `" << section_
      << ":` section; flags given on the command line win\n";
  return out.str();
}

}  // namespace auv::recon
