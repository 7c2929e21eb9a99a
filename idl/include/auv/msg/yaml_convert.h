#pragma once
// YAML encoding of message fields, used by the generated toYaml/fromYaml functions.
// Errors name the field by its dotted path so `auv topic pub` can say what is wrong.

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "auv/msg/type_support.h"

namespace auv::msg::detail {

inline std::string join(const std::string& path, const std::string& field) {
  return path.empty() ? field : path + "." + field;
}

inline std::string describe(const YAML::Node& node) {
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  if (node.IsSequence()) return "a list";
  if (node.IsMap()) return "a map";
  return "nothing";
}

[[noreturn]] inline void fail(const std::string& path, const std::string& expected,
                              const YAML::Node& node) {
  throw std::invalid_argument("field '" + (path.empty() ? std::string("<root>") : path) +
                              "': expected " + expected + ", got " + describe(node));
}

/// Rejects keys that are not fields of the struct (typos would otherwise be silently ignored).
void checkFields(const YAML::Node& node, const std::string& path,
                 std::initializer_list<const char*> fields);

template <class T>
struct IsVector : std::false_type {};
template <class T>
struct IsVector<std::vector<T>> : std::true_type {};
template <class T>
struct IsArray : std::false_type {};
template <class T, size_t N>
struct IsArray<std::array<T, N>> : std::true_type {};

template <class T>
YAML::Node encode(const T& value) {
  if constexpr (std::is_same_v<T, bool> || std::is_same_v<T, std::string>) {
    return YAML::Node(value);
  } else if constexpr (std::is_enum_v<T>) {
    const auto index = static_cast<size_t>(value);
    const auto& names = EnumTraits<T>::kNames;
    return index < names.size() ? YAML::Node(names[index]) : YAML::Node(index);
  } else if constexpr (std::is_integral_v<T>) {
    return YAML::Node(
        static_cast<std::conditional_t<std::is_signed_v<T>, int64_t, uint64_t>>(value));
  } else if constexpr (std::is_floating_point_v<T>) {
    return YAML::Node(static_cast<double>(value));
  } else if constexpr (IsVector<T>::value || IsArray<T>::value) {
    YAML::Node seq(YAML::NodeType::Sequence);
    for (const auto& element : value) seq.push_back(encode(element));
    return seq;
  } else {
    return toYaml(value);  // a generated struct, found by argument-dependent lookup
  }
}

template <class T>
void decode(const YAML::Node& node, T& value, const std::string& path) {
  if constexpr (std::is_same_v<T, bool>) {
    if (!node.IsScalar() || (node.Scalar() != "true" && node.Scalar() != "false"))
      fail(path, "true or false", node);
    value = node.Scalar() == "true";
  } else if constexpr (std::is_same_v<T, std::string>) {
    if (!node.IsScalar()) fail(path, "a string", node);
    value = node.Scalar();
  } else if constexpr (std::is_enum_v<T>) {
    const auto& names = EnumTraits<T>::kNames;
    if (node.IsScalar()) {
      for (size_t i = 0; i < names.size(); ++i) {
        if (node.Scalar() == names[i]) {
          value = static_cast<T>(i);
          return;
        }
      }
    }
    std::string choices;
    for (const char* n : names) choices += std::string(choices.empty() ? "" : ", ") + n;
    fail(path, "one of [" + choices + "]", node);
  } else if constexpr (std::is_integral_v<T>) {
    using Wide = std::conditional_t<std::is_signed_v<T>, long long, unsigned long long>;
    Wide wide{};
    if (!node.IsScalar() || !YAML::convert<Wide>::decode(node, wide) ||
        (std::is_unsigned_v<T> && !node.Scalar().empty() && node.Scalar()[0] == '-'))
      fail(path, "an integer", node);
    if (wide < static_cast<Wide>(std::numeric_limits<T>::min()) ||
        wide > static_cast<Wide>(std::numeric_limits<T>::max()))
      fail(path,
           "an integer in [" + std::to_string(+std::numeric_limits<T>::min()) + ", " +
               std::to_string(+std::numeric_limits<T>::max()) + "]",
           node);
    value = static_cast<T>(wide);
  } else if constexpr (std::is_floating_point_v<T>) {
    double d = 0;
    if (!node.IsScalar() || !YAML::convert<double>::decode(node, d)) fail(path, "a number", node);
    value = static_cast<T>(d);
  } else if constexpr (IsVector<T>::value) {
    if (!node.IsSequence()) fail(path, "a list", node);
    value.clear();
    value.resize(node.size());
    for (size_t i = 0; i < node.size(); ++i)
      decode(node[i], value[i], path + "[" + std::to_string(i) + "]");
  } else if constexpr (IsArray<T>::value) {
    if (!node.IsSequence() || node.size() != value.size())
      fail(path, "a list of " + std::to_string(value.size()) + " elements", node);
    for (size_t i = 0; i < node.size(); ++i)
      decode(node[i], value[i], path + "[" + std::to_string(i) + "]");
  } else {
    fromYaml(node, value, path);  // a generated struct
  }
}

}  // namespace auv::msg::detail
