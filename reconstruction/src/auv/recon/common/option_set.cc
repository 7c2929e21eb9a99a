#include "auv/recon/common/option_set.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <limits>
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

[[noreturn]] void bad(const std::string& where, const std::string& text, const char* expected) {
  throw std::invalid_argument(where + ": expected " + expected + ", got '" + text + "'");
}

template <class T>
T parseValue(const std::string& where, const std::string& text);

template <>
double parseValue<double>(const std::string& where, const std::string& text) {
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(v)) {
    bad(where, text, "a number");
  }
  return v;
}
template <>
float parseValue<float>(const std::string& where, const std::string& text) {
  return static_cast<float>(parseValue<double>(where, text));
}
template <>
int64_t parseValue<int64_t>(const std::string& where, const std::string& text) {
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || errno == ERANGE) bad(where, text, "an integer");
  return v;
}
template <>
int parseValue<int>(const std::string& where, const std::string& text) {
  const int64_t v = parseValue<int64_t>(where, text);
  if (v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max()) {
    bad(where, text, "an integer in the int range");
  }
  return static_cast<int>(v);
}
template <>
uint64_t parseValue<uint64_t>(const std::string& where, const std::string& text) {
  const int64_t v = parseValue<int64_t>(where, text);
  if (v < 0) bad(where, text, "a non-negative integer");
  return static_cast<uint64_t>(v);
}
template <>
unsigned parseValue<unsigned>(const std::string& where, const std::string& text) {
  const uint64_t v = parseValue<uint64_t>(where, text);
  if (v > std::numeric_limits<unsigned>::max()) bad(where, text, "a smaller integer");
  return static_cast<unsigned>(v);
}
template <>
bool parseValue<bool>(const std::string& where, const std::string& text) {
  if (text == "true" || text == "1" || text == "yes" || text == "on") return true;
  if (text == "false" || text == "0" || text == "no" || text == "off") return false;
  bad(where, text, "true or false");
}
template <>
std::string parseValue<std::string>(const std::string&, const std::string& text) {
  return text;
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

std::string scalarText(const YAML::Node& node, const std::string& where) {
  if (!node.IsScalar()) throw std::invalid_argument(where + ": expected a single value");
  return node.Scalar();
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
        for (const auto& item : node) value->push_back(scalarText(item, where));
      } else {
        value->push_back(scalarText(node, where));
      }
    };
  } else {
    using Parsed = T;
    e.type = typeName<T>();
    e.default_text = showDefault(*value);
    e.is_flag = std::is_same_v<T, bool>;
    e.set = [value, name](const std::string& text) {
      *value = static_cast<T>(parseValue<Parsed>(flagName(name), text));
    };
    e.set_yaml = [value](const YAML::Node& node, const std::string& where) {
      *value = static_cast<T>(parseValue<Parsed>(where, scalarText(node, where)));
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
  YAML::Node root;
  try {
    root = YAML::LoadFile(file.string());
  } catch (const YAML::BadFile&) {
    throw std::invalid_argument("--config: " + file.string() + ": cannot read");
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument("--config: " + file.string() + ": " + e.what());
  }
  if (!root || root.IsNull()) return;
  if (!root.IsMap()) {
    throw std::invalid_argument(file.string() + ": expected a map of stage sections");
  }
  if (root[section_]) applyYaml(root[section_], file.string() + ": " + section_);
}

void OptionSet::applyYaml(const YAML::Node& section, const std::string& where) {
  if (section.IsNull()) return;
  if (!section.IsMap()) throw std::invalid_argument(where + ": expected a map of options");
  for (const auto& item : section) {
    const std::string key = item.first.as<std::string>();
    Entry* e = find(key);
    if (e == nullptr) {
      std::string known;
      for (const auto& entry : entries_) known += (known.empty() ? "" : ", ") + entry.name;
      throw std::invalid_argument(where + "." + key + ": unknown option (known: " + known + ")");
    }
    e->set_yaml(item.second, where + "." + key);
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
