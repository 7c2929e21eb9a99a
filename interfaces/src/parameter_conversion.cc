// Strict YAML 1.2 conversion of parameter values and constraint checking (see
// parameter_conversion.h).

#include "parameter_conversion.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <system_error>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "auv/config/yaml_scalars.h"

namespace auv::interfaces::detail {
namespace {

bool isNumeric(ParameterType type) {
  return type == ParameterType::INTEGER || type == ParameterType::DOUBLE ||
         type == ParameterType::INTEGER_ARRAY || type == ParameterType::DOUBLE_ARRAY;
}

bool isString(ParameterType type) {
  return type == ParameterType::STRING || type == ParameterType::STRING_ARRAY;
}

std::string joinStrings(const std::vector<std::string>& values) { return formatList(values); }

// Clamps a double to int64_t (NaN is handled by the callers' descriptor check).
int64_t clampToInt64(double value) {
  if (!(value > -9.223372036854775808e18)) return kInt64Min;
  if (value >= 9.223372036854775808e18) return kInt64Max;
  return static_cast<int64_t>(value);
}

// " in [a, b]", " >= a", " <= b" or "" for the numeric range of a declaration.
std::string rangeText(const Declared& declared, ParameterType type) {
  std::optional<std::string> low;
  std::optional<std::string> high;
  if (isInteger(type)) {
    const auto [int_low, int_high] = integerBounds(declared);
    if (int_low != kInt64Min) low = std::to_string(int_low);
    if (int_high != kInt64Max) high = std::to_string(int_high);
  } else {
    if (declared.descriptor.min) low = formatDouble(*declared.descriptor.min);
    if (declared.descriptor.max) high = formatDouble(*declared.descriptor.max);
  }
  // Integer bounds are always inclusive (integerBounds rounds exclusive ones inwards).
  const bool open_low = !isInteger(type) && declared.descriptor.min_exclusive;
  const bool open_high = !isInteger(type) && declared.descriptor.max_exclusive;
  if (low && high) {
    return std::string(" in ") + (open_low ? "(" : "[") + *low + ", " + *high +
           (open_high ? ")" : "]");
  }
  if (low) return (open_low ? " > " : " >= ") + *low;
  if (high) return (open_high ? " < " : " <= ") + *high;
  return "";
}

// What a value of this declaration must look like: "a number in [0.1, 50]".
std::string expectation(const Declared& declared) {
  const ParameterType type = typeOf(declared.value);
  const auto& choices = declared.descriptor.choices;
  switch (type) {
    case ParameterType::BOOL:
      return "a boolean (true or false)";
    case ParameterType::INTEGER:
      return "an integer" + rangeText(declared, type);
    case ParameterType::DOUBLE:
      return "a number" + rangeText(declared, type);
    case ParameterType::STRING:
      return choices.empty() ? "a string" : "one of " + joinStrings(choices);
    case ParameterType::BOOL_ARRAY:
      return "a list of booleans (true or false)";
    case ParameterType::INTEGER_ARRAY:
      return "a list of integers" + rangeText(declared, type);
    case ParameterType::DOUBLE_ARRAY:
      return "a list of numbers" + rangeText(declared, type);
    case ParameterType::STRING_ARRAY:
      return choices.empty() ? "a list of strings"
                             : "a list of strings, each one of " + joinStrings(choices);
  }
  return "a value";
}

}  // namespace

bool isInteger(ParameterType type) {
  return type == ParameterType::INTEGER || type == ParameterType::INTEGER_ARRAY;
}

std::string formatDouble(double value) {
  if (std::isnan(value)) return ".nan";
  if (std::isinf(value)) return value > 0 ? ".inf" : "-.inf";
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

std::pair<int64_t, int64_t> integerBounds(const Declared& declared) {
  int64_t low = declared.int_min;
  int64_t high = declared.int_max;
  const auto& d = declared.descriptor;
  if (d.min) {
    const double first = d.min_exclusive ? std::floor(*d.min) + 1 : std::ceil(*d.min);
    low = std::max(low, clampToInt64(first));
  }
  if (d.max) {
    const double last = d.max_exclusive ? std::ceil(*d.max) - 1 : std::floor(*d.max);
    high = std::min(high, clampToInt64(last));
  }
  return {low, high};
}

// ---------------------------------------------------------------------------------------------
// Scalar text conversion: the one YAML 1.2 core-schema rule of auv/config/yaml_scalars.h.

namespace {

using config::isPlainScalar;
using config::nodeText;

// Converts one YAML scalar node to `Stored`; numbers and booleans must be plain (unquoted).
template <class Stored>
std::optional<Stored> scalarFromNode(const YAML::Node& node) {
  if (!node.IsScalar()) return std::nullopt;
  if constexpr (std::is_same_v<Stored, std::string>) {
    return node.Scalar();
  } else {
    if (!isPlainScalar(node)) return std::nullopt;
    if constexpr (std::is_same_v<Stored, bool>) {
      return config::parseBool(node.Scalar());
    } else if constexpr (std::is_same_v<Stored, int64_t>) {
      return config::parseInteger(node.Scalar());
    } else {
      return config::parseNumber(node.Scalar());
    }
  }
}

template <class Stored>
Conversion convertNode(const YAML::Node& node, bool array) {
  Conversion conversion;
  if (!array) {
    if (auto scalar = scalarFromNode<Stored>(node)) conversion.value = ParameterValue(*scalar);
    return conversion;
  }
  if (!node.IsSequence()) return conversion;
  std::vector<Stored> values;
  for (size_t i = 0; i < node.size(); ++i) {
    auto scalar = scalarFromNode<Stored>(node[i]);
    if (!scalar) {
      conversion.violation = {i, nodeText(node[i])};
      return conversion;
    }
    values.push_back(*scalar);
  }
  conversion.value = ParameterValue(std::move(values));
  return conversion;
}

}  // namespace

Conversion convertNode(const YAML::Node& node, ParameterType type) {
  switch (type) {
    case ParameterType::BOOL:
      return convertNode<bool>(node, false);
    case ParameterType::INTEGER:
      return convertNode<int64_t>(node, false);
    case ParameterType::DOUBLE:
      return convertNode<double>(node, false);
    case ParameterType::STRING:
      return convertNode<std::string>(node, false);
    case ParameterType::BOOL_ARRAY:
      return convertNode<bool>(node, true);
    case ParameterType::INTEGER_ARRAY:
      return convertNode<int64_t>(node, true);
    case ParameterType::DOUBLE_ARRAY:
      return convertNode<double>(node, true);
    case ParameterType::STRING_ARRAY:
      return convertNode<std::string>(node, true);
  }
  return {};
}

// ---------------------------------------------------------------------------------------------
// Constraint checks (value already has the declared type).

namespace {

bool elementOk(const Declared& declared, int64_t value) {
  const auto [low, high] = integerBounds(declared);
  return value >= low && value <= high;
}

bool elementOk(const Declared& declared, double value) {
  const auto& d = declared.descriptor;
  // NaN fails any bound.
  if (d.min && !(d.min_exclusive ? value > *d.min : value >= *d.min)) return false;
  if (d.max && !(d.max_exclusive ? value < *d.max : value <= *d.max)) return false;
  return true;
}

bool elementOk(const Declared& declared, const std::string& value) {
  const auto& choices = declared.descriptor.choices;
  return choices.empty() || std::find(choices.begin(), choices.end(), value) != choices.end();
}

bool elementOk(const Declared& /*declared*/, bool /*value*/) { return true; }

}  // namespace

std::optional<Violation> checkConstraints(const Declared& declared, const ParameterValue& value) {
  return std::visit(
      [&](const auto& v) -> std::optional<Violation> {
        using V = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<V, std::vector<bool>> ||
                      std::is_same_v<V, std::vector<int64_t>> ||
                      std::is_same_v<V, std::vector<double>> ||
                      std::is_same_v<V, std::vector<std::string>>) {
          using E = typename V::value_type;
          for (size_t i = 0; i < v.size(); ++i) {
            const E element = v[i];
            if (!elementOk(declared, element)) return Violation{i, formatScalar<E>(element)};
          }
          return std::nullopt;
        } else {
          if (!elementOk(declared, v)) return Violation{};
          return std::nullopt;
        }
      },
      value);
}

std::string expectedGot(const Declared& declared, const std::string& got,
                        const Violation& violation) {
  std::string text = "expected " + expectation(declared) + ", got " + got;
  if (violation.element) {
    text +=
        " (element " + std::to_string(*violation.element) + ": '" + violation.element_text + "')";
  }
  return text;
}

ParameterValue coerce(const ParameterValue& value, ParameterType type) {
  if (type == ParameterType::DOUBLE && std::holds_alternative<int64_t>(value)) {
    return static_cast<double>(std::get<int64_t>(value));
  }
  if (type == ParameterType::DOUBLE_ARRAY && std::holds_alternative<std::vector<int64_t>>(value)) {
    const auto& integers = std::get<std::vector<int64_t>>(value);
    return std::vector<double>(integers.begin(), integers.end());
  }
  return value;
}

void checkDescriptor(const std::string& name, const Declared& declared) {
  const ParameterType type = typeOf(declared.value);
  const auto& d = declared.descriptor;
  const std::string prefix = "parameter '" + name + "': invalid declaration: ";
  if ((d.min && std::isnan(*d.min)) || (d.max && std::isnan(*d.max))) {
    throw ParameterError(prefix + "min/max must not be NaN");
  }
  if ((d.min || d.max) && !isNumeric(type)) {
    throw ParameterError(prefix + "min/max apply to numbers, but the type is " + toString(type));
  }
  if (d.min && d.max &&
      (*d.min > *d.max || (*d.min == *d.max && (d.min_exclusive || d.max_exclusive)))) {
    throw ParameterError(prefix + "min " + formatDouble(*d.min) + " > max " + formatDouble(*d.max));
  }
  if (isInteger(type)) {
    const auto [low, high] = integerBounds(declared);
    if (low > high) {
      throw ParameterError(prefix + "no integer lies in the allowed range" +
                           rangeText(declared, type));
    }
  }
  if (!d.choices.empty() && !isString(type)) {
    throw ParameterError(prefix + "choices apply to strings, but the type is " + toString(type));
  }
}

}  // namespace auv::interfaces::detail
