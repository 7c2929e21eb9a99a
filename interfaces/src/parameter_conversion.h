#pragma once
// Strict YAML 1.2 conversion of parameter values and checking of declared constraints, for
// Parameters (parameters.cc): YAML scalars and sequences become ParameterValues by the rules in
// the file comment of auv/interfaces/parameters.h, values are checked against their declaration
// (C++ integer range, min/max, choices), and rejections are worded as "expected ..., got ...".

#include "auv/interfaces/parameters.h"

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <yaml-cpp/yaml.h>

namespace auv::interfaces::detail {

/// Smallest int64_t; an integer bound equal to it means "no lower bound".
inline constexpr int64_t kInt64Min = std::numeric_limits<int64_t>::min();
/// Largest int64_t; an integer bound equal to it means "no upper bound".
inline constexpr int64_t kInt64Max = std::numeric_limits<int64_t>::max();

/// A declared parameter.
struct Declared {
  ParameterValue value;            // current value; its index is the declared type
  ParameterDescriptor descriptor;  // as declared
  int64_t int_min;                 // range of the C++ integer type (integers only)
  int64_t int_max;
  std::string source;  // where the current value came from: "default", a file, "set()"
};

/// Why a value was rejected: element index in an array, if the fault is one element.
struct Violation {
  std::optional<size_t> element;  // faulty element of an array value
  std::string element_text;       // that element as written
};

/// True for INTEGER and INTEGER_ARRAY.
bool isInteger(ParameterType type);

/// Formats a double as in messages: shortest round-trip text, or .nan, .inf, -.inf.
std::string formatDouble(double value);

/// Formats one scalar as in messages: true, 5, 2.5, fast, or "" for an empty string.
template <class T>
std::string formatScalar(const T& value) {
  if constexpr (std::is_same_v<T, bool>) {
    return value ? "true" : "false";
  } else if constexpr (std::is_same_v<T, int64_t>) {
    return std::to_string(value);
  } else if constexpr (std::is_same_v<T, double>) {
    return formatDouble(value);
  } else {
    return value.empty() ? std::string("\"\"") : value;
  }
}

/// Formats a list as in messages: [0.1, 2], [a, b].
template <class T>
std::string formatList(const std::vector<T>& values) {
  std::string text = "[";
  for (size_t i = 0; i < values.size(); ++i) {
    if (i > 0) text += ", ";
    text += formatScalar<T>(values[i]);
  }
  return text + "]";
}

/// Effective inclusive bounds of an integer parameter: C++ type range and descriptor together.
std::pair<int64_t, int64_t> integerBounds(const Declared& declared);

/// Result of converting a YAML node: the value, or the violation.
struct Conversion {
  std::optional<ParameterValue> value;
  Violation violation;
};

/// Converts a YAML node to a value of `type` by the strict YAML 1.2 core schema rules.
Conversion convertNode(const YAML::Node& node, ParameterType type);

/// Checks a value that already has the declared type against the declaration's constraints.
std::optional<Violation> checkConstraints(const Declared& declared, const ParameterValue& value);

/// "expected <expectation>, got <display> (element i: x)".
std::string expectedGot(const Declared& declared, const std::string& got,
                        const Violation& violation);

/// Converts int64_t (arrays) to double (arrays) for double parameters; other values unchanged.
ParameterValue coerce(const ParameterValue& value, ParameterType type);

/// Throws if a descriptor cannot apply to a parameter of `type`.
void checkDescriptor(const std::string& name, const Declared& declared);

}  // namespace auv::interfaces::detail
