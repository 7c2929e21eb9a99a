#include "launch_arguments.h"

#include <cstdlib>
#include <optional>

#include "auv/config/spelling.h"
#include "launch_description.h"

namespace auv::bringup {
namespace {

std::string declaredList(const std::vector<LaunchArgument>& declared) {
  std::string list;
  for (const LaunchArgument& a : declared) list += (list.empty() ? "" : ", ") + a.name;
  return list.empty() ? "none" : list;
}

std::string closest(const std::string& name, const std::vector<LaunchArgument>& declared) {
  std::vector<std::string> names;
  for (const LaunchArgument& a : declared) names.push_back(a.name);
  return config::closestMatch(name, names);
}

/// The value of $(env name [default]): the variable when set and not empty, else the default.
std::string environmentValue(const std::string& name, const std::optional<std::string>& fallback,
                             const std::string& source, const std::string& path) {
  const char* value = std::getenv(name.c_str());
  if (value && *value) return value;
  if (fallback) return *fallback;
  throw LaunchFileError(source, path,
                        "$(env " + name + ") refers to an environment variable that is not set " +
                            "(export it, or give a default: $(env " + name + " <default>))");
}

/// One $(arg name) or $(env name [default]) in a string.
struct Substitution {
  std::string kind;  // "arg" or "env"
  std::string name;
  std::optional<std::string> fallback;  // the default: up to the ')', without trailing spaces
  size_t end = 0;                       // just after the ')'
};

// ASCII only, whatever the locale.
bool isSpace(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\v' || c == '\f' || c == '\r';
}
bool isNameChar(char c, bool first) {
  return c == '_' || (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') ||
         (!first && c >= '0' && c <= '9');
}

/// The substitution `$((arg|env)\s+NAME(\s+DEFAULT)?\s*)` at `start` (where "$(" is), DEFAULT
/// starting with neither a space nor a parenthesis and holding no parenthesis; nothing if the
/// text there is not one. A scan, not std::regex: its matcher recurses once per character and
/// overflows the stack on a long string (a 100 kB command line in a launch file).
std::optional<Substitution> substitutionAt(const std::string& text, size_t start) {
  const size_t n = text.size();
  size_t i = start + 2;
  Substitution s;
  if (text.compare(i, 3, "arg") == 0 || text.compare(i, 3, "env") == 0) {
    s.kind = text.substr(i, 3);
  } else {
    return std::nullopt;
  }
  i += 3;
  if (i >= n || !isSpace(text[i])) return std::nullopt;
  while (i < n && isSpace(text[i])) ++i;
  if (i >= n || !isNameChar(text[i], true)) return std::nullopt;
  const size_t name_start = i;
  while (i < n && isNameChar(text[i], false)) ++i;
  s.name = text.substr(name_start, i - name_start);
  const size_t name_end = i;
  while (i < n && isSpace(text[i])) ++i;
  if (i >= n) return std::nullopt;
  if (text[i] == ')') {
    s.end = i + 1;
    return s;
  }
  if (i == name_end || text[i] == '(') return std::nullopt;
  const size_t close = text.find_first_of("()", i);
  if (close == std::string::npos || text[close] == '(') return std::nullopt;
  size_t fallback_end = close;
  while (isSpace(text[fallback_end - 1])) --fallback_end;
  s.fallback = text.substr(i, fallback_end - i);
  s.end = close + 1;
  return s;
}

/// `text` with every $(arg name) replaced by its value and every $(env name [default]) by the
/// environment's; errors name `path`.
std::string substituteText(const std::string& text,
                           const std::map<std::string, std::string>& values,
                           const std::vector<LaunchArgument>& declared, const std::string& source,
                           const std::string& path) {
  if (text.find("$(") == std::string::npos) return text;
  std::string out;
  size_t last = 0;
  for (size_t at = text.find("$("); at != std::string::npos; at = text.find("$(", at + 1)) {
    const std::optional<Substitution> match = substitutionAt(text, at);
    if (!match) continue;  // left as it is: the check below names it
    const std::string& kind = match->kind;
    const std::string& name = match->name;
    const std::optional<std::string>& fallback = match->fallback;
    std::string replacement;
    if (kind == "env") {
      replacement = environmentValue(name, fallback, source, path);
    } else {
      if (fallback) {
        throw LaunchFileError(source, path,
                              "$(arg " + name + " ...) takes no default here; declare it under " +
                                  "arguments: {" + name + ": {default: ...}}");
      }
      const auto value = values.find(name);
      if (value == values.end()) {
        const std::string hint = closest(name, declared);
        throw LaunchFileError(source, path,
                              "$(arg " + name + ") refers to an undeclared argument" +
                                  (hint.empty() ? "" : " (did you mean '" + hint + "'?)") +
                                  "; declared: " + declaredList(declared));
      }
      replacement = value->second;
    }
    out += text.substr(last, at - last) + replacement;
    last = match->end;
    at = match->end - 1;
  }
  out += text.substr(last);
  if (out.find("$(") != std::string::npos) {
    throw LaunchFileError(
        source, path,
        "malformed substitution in '" + text + "' (expected $(arg name) or $(env NAME [default]))");
  }
  return out;
}

void substitute(YAML::Node node, const std::map<std::string, std::string>& values,
                const std::vector<LaunchArgument>& declared, const std::string& source,
                const std::string& path) {
  if (node.IsScalar()) {
    const std::string text = node.Scalar();
    if (text.find("$(") == std::string::npos) return;
    node = substituteText(text, values, declared, source, path);
    return;
  }
  if (node.IsSequence()) {
    for (size_t i = 0; i < node.size(); ++i) {
      substitute(node[i], values, declared, source, path + "[" + std::to_string(i) + "]");
    }
  } else if (node.IsMap()) {
    for (auto entry : node) {
      const std::string key = entry.first.Scalar();
      substitute(entry.second, values, declared, source, path.empty() ? key : path + "." + key);
    }
  }
}

}  // namespace

std::vector<LaunchArgument> applyLaunchArguments(YAML::Node& root,
                                                 const std::map<std::string, std::string>& given,
                                                 const std::string& source) {
  std::vector<LaunchArgument> declared;
  if (root.IsMap() && root["arguments"]) {
    const YAML::Node args = root["arguments"];
    if (!args.IsMap()) {
      throw LaunchFileError(source, "arguments",
                            "expected a mapping of name: {default, description}");
    }
    for (auto entry : args) {
      LaunchArgument a;
      a.name = entry.first.Scalar();
      const std::string path = "arguments." + a.name;
      if (entry.second.IsScalar()) {
        a.default_value = entry.second.Scalar();
        a.has_default = true;
      } else if (entry.second.IsMap()) {
        for (auto field : entry.second) {
          const std::string key = field.first.Scalar();
          if (key == "default" && field.second.IsScalar()) {
            a.default_value = field.second.Scalar();
            a.has_default = true;
          } else if (key == "description" && field.second.IsScalar()) {
            a.description = field.second.Scalar();
          } else {
            throw LaunchFileError(source, path + "." + key,
                                  "unknown or non-scalar key; expected default, description");
          }
        }
      } else if (!entry.second.IsNull()) {
        throw LaunchFileError(source, path, "expected a default value or {default, description}");
      }
      declared.push_back(a);
    }
    root.remove("arguments");
  }
  std::map<std::string, std::string> values;
  for (const LaunchArgument& a : declared) {
    if (a.has_default) values[a.name] = a.default_value;
  }
  for (const auto& [name, value] : given) {
    bool known = false;
    for (const LaunchArgument& a : declared) known = known || a.name == name;
    if (!known) {
      const std::string hint = closest(name, declared);
      throw LaunchFileError(source, "arguments",
                            "'" + name + ":=" + value + "' sets an undeclared argument" +
                                (hint.empty() ? "" : " (did you mean '" + hint + "'?)") +
                                "; declared: " + declaredList(declared));
    }
    values[name] = value;
  }
  // A value may use the arguments declared before it: run_dir: "runs/$(arg world)".
  std::map<std::string, std::string> resolved;
  for (LaunchArgument& a : declared) {
    if (!values.count(a.name)) {
      throw LaunchFileError(source, "arguments." + a.name,
                            "required argument not given (add " + a.name + ":=<value>)");
    }
    a.default_value =
        substituteText(values[a.name], resolved, declared, source, "arguments." + a.name);
    resolved[a.name] = values[a.name] = a.default_value;
  }
  substitute(root, values, declared, source, "");
  return declared;
}

}  // namespace auv::bringup
