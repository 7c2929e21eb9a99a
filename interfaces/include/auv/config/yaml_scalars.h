#pragma once
// The one scalar rule of every YAML reader of auv-inspect (parameter files, scenarios, missions,
// reconstruction options, launch files; docs/architecture.md, "Reading YAML"): the YAML 1.2
// core schema, strictly.
//
//   boolean  true True TRUE false False FALSE            (not yes/no/on/off/y/n/1/0: YAML 1.1)
//   integer  [-+]?[0-9]+, 0x[0-9a-fA-F]+, 0o[0-7]+       (not 1_000, 0b101, -0x10, 1e3, 1.0)
//   number   an integer, [-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?,
//            [-+]?.inf, .nan (any of .inf .Inf .INF; the readers that need finite values
//            refuse them)
//
// Only plain (unquoted, untagged) scalars are numbers or booleans: "5" and 'true' are strings.
// Messages show the value as written: 'abc', "5" (a quoted string), null (empty value), a map.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include <yaml-cpp/yaml.h>

namespace auv::config {

/// A YAML 1.2 core boolean, or nullopt.
std::optional<bool> parseBool(const std::string& text);
/// A YAML 1.2 core integer (decimal, 0x hex, 0o octal) in the int64_t range, or nullopt.
std::optional<int64_t> parseInteger(const std::string& text);
/// A YAML 1.2 core number (an integer or a float, .inf and .nan included), or nullopt.
std::optional<double> parseNumber(const std::string& text);

/// True for a plain scalar (written without quotes or a tag): only those are numbers/booleans.
bool isPlainScalar(const YAML::Node& node);
/// The node as written, for messages: abc, "5" (quoted), [1, abc], null, {...}.
std::string nodeText(const YAML::Node& node);
/// The "got ..." part of a message: 'abc', "5" (a quoted string), null (empty value), a map,
/// '[1, abc]'.
std::string describeNode(const YAML::Node& node);

/// ":line:column" (1-based) of a mark, "" for a null mark: "file.yaml:3:7: ..." in messages.
std::string markText(const YAML::Mark& mark);

/// Most nodes that the aliases of one document may stand for, in all (an alias counts the nodes
/// of what it refers to). Ample for a settings file that shares a few lists and maps; each
/// aliased node may become a parameter with a long dotted name, so the bound is kept low.
inline constexpr std::size_t kMaxAliasedNodes = 10000;

/// YAML::Load of every reader: the first document of `text`, refusing two documents yaml-cpp
/// composes but no reader can walk: an alias inside the node it refers to (`&a [*a]`, a node
/// that contains itself: every walk of it is endless) and aliases standing for more than
/// kMaxAliasedNodes nodes (aliases of aliases grow a few lines into billions of nodes). Both
/// throw a YAML::ParserException at the alias, reported by the readers like a syntax error
/// ("<file>:<line>:<column>: malformed YAML: ...").
YAML::Node loadYaml(const std::string& text);

}  // namespace auv::config
