// Typed, declared parameters for auv-inspect components, configured from YAML files and
// command-line overrides and validated when declared (in the spirit of ROS 2 parameters).
//
// Life cycle: the runner constructs `Parameters(node_name)`, loads parameter files
// (`loadFile`) and command-line assignments (`setOverride`), then the component declares its
// parameters in `configure()` (`declare<T>`), which is where values are converted and validated;
// a bad value throws ParameterError naming the parameter and the file. Afterwards the runner
// warns about `unusedOverrides()` (typos), and `set()` changes values at runtime.
//
// YAML file format (a ROS 2 params file without the `ros__parameters` level, which is also
// accepted and skipped):
//
//   /**:                 # or "*": applies to every node
//     use_sim_time: false
//   planner:             # node name (a leading '/' is ignored)
//     mode: fast
//     planner:           # nested maps flatten to dotted names: planner.range
//       range: 2.0
//     weights: [0.5, 0.25]
//
// Precedence (highest first): command-line overrides (`setOverride`, whatever the load order),
// then node-specific sections, then wildcard sections; within one level, later loads override
// earlier ones. Files must be loaded before the parameters they set are declared.
//
// Conversion rules (strict, YAML 1.2 core schema):
//   bool     plain true/false (also True/TRUE/False/FALSE); yes/no/on/off/1/0 are errors.
//   integer  plain decimal, 0x hex or 0o octal integer; 1.5, 1e3 and "5" (quoted) are errors;
//            the C++ type's range applies (declare<uint8_t> rejects 300 and -1).
//   double   plain integer or decimal/exponent number, .inf, -.inf, .nan; "abc" is an error.
//   string   any scalar, taken as written (quote it to keep e.g. leading zeros); null is an error.
//   arrays   a YAML sequence ([a, b] or block) whose elements follow the scalar rules; [] is empty.
//
// Thread safety: all member functions may be called concurrently (e.g. a timer reading with
// get() while the CLI calls set()). set() calls are serialized; onSet callbacks run without the
// internal lock held, so they may call get() but must not call set() or declare().
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "auv/config/errors.h"

namespace auv::interfaces {

/// Thrown for bad parameter files, bad values, bad declarations and bad get() requests: the
/// user's input is wrong (exit code 2, auv/config/errors.h).
class ParameterError : public config::ConfigError {
 public:
  using config::ConfigError::ConfigError;
};

/// A parameter value; the alternative's index is its ParameterType.
using ParameterValue =
    std::variant<bool, int64_t, double, std::string, std::vector<bool>, std::vector<int64_t>,
                 std::vector<double>, std::vector<std::string>>;

/// The type of a parameter, in the order of the ParameterValue alternatives.
enum class ParameterType {
  BOOL,
  INTEGER,
  DOUBLE,
  STRING,
  BOOL_ARRAY,
  INTEGER_ARRAY,
  DOUBLE_ARRAY,
  STRING_ARRAY,
};

/// Type name used in messages and describe(): "bool", "integer", ..., "string_array".
std::string toString(ParameterType type);

/// Type of the alternative held by `value`.
inline ParameterType typeOf(const ParameterValue& value) {
  return static_cast<ParameterType>(value.index());
}

/// Formats a value as in messages: 2.5, true, fast, [0.1, 2], [a, b].
std::string toString(const ParameterValue& value);

/// Source name to pass to Parameters::setOverride for `-p name:=value` arguments.
inline constexpr char kCommandLineSource[] = "command line (-p)";

/// What a declaration says about a parameter (shown by `auv run <component> --help`).
struct ParameterDescriptor {
  std::string description;           // one line: what it does
  std::string unit;                  // SI unit, e.g. "m", "m/s", "rad"; empty if none
  std::optional<double> min;         // lower bound for numbers / numeric array elements
  std::optional<double> max;         // upper bound for numbers / numeric array elements
  std::vector<std::string> choices;  // allowed values for strings / string array elements
  bool read_only = false;            // if true, set() rejects runtime changes
  bool min_exclusive = false;        // min itself is not allowed: (min, ...
  bool max_exclusive = false;        // max itself is not allowed: ..., max)
};

namespace detail {

/// Throws ParameterError: the value of `name` does not fit in the requested C++ integer type.
[[noreturn]] void throwDoesNotFit(const std::string& name, const std::string& value, int64_t min,
                                  int64_t max);
/// Throws ParameterError: `name` is declared as `declared` but was requested as `requested`.
[[noreturn]] void throwWrongType(const std::string& name, ParameterType declared,
                                 ParameterType requested);

/// True for integral types other than bool.
template <class T>
inline constexpr bool kIsInteger = std::is_integral_v<T> && !std::is_same_v<T, bool>;

/// Smallest value of integer type T, as int64_t.
template <class T>
constexpr int64_t integerMin() {
  if constexpr (std::is_signed_v<T>) {
    return std::numeric_limits<T>::min();
  } else {
    return 0;
  }
}

/// Largest value of integer type T that int64_t can hold.
template <class T>
constexpr int64_t integerMax() {
  if constexpr (std::is_unsigned_v<T> && sizeof(T) >= sizeof(int64_t)) {
    return std::numeric_limits<int64_t>::max();
  } else {
    return static_cast<int64_t>(std::numeric_limits<T>::max());
  }
}

/// Element type of std::vector<T>, or T itself.
template <class T>
struct Element {
  using type = T;
};
/// Element type of std::vector<T>.
template <class T>
struct Element<std::vector<T>> {
  using type = T;
};

/// Maps a C++ scalar type to its stored type; unsupported types have kSupported = false.
template <class T, class Enable = void>
struct ScalarTraits {
  static constexpr bool kSupported = false;
};

/// bool is stored as bool.
template <>
struct ScalarTraits<bool> {
  static constexpr bool kSupported = true;
  static constexpr ParameterType kType = ParameterType::BOOL;
  static constexpr ParameterType kArrayType = ParameterType::BOOL_ARRAY;
  static constexpr int64_t kMin = std::numeric_limits<int64_t>::min();
  static constexpr int64_t kMax = std::numeric_limits<int64_t>::max();
  using Stored = bool;
  static bool toStored(const std::string& /*name*/, bool value) { return value; }
  static bool fromStored(const std::string& /*name*/, bool value) { return value; }
};

/// Integral types are stored as int64_t; their own range becomes part of the declaration.
template <class T>
struct ScalarTraits<T, std::enable_if_t<kIsInteger<T>>> {
  static_assert(sizeof(T) <= sizeof(int64_t), "integer parameters are at most 64 bits");
  static constexpr bool kSupported = true;
  static constexpr ParameterType kType = ParameterType::INTEGER;
  static constexpr ParameterType kArrayType = ParameterType::INTEGER_ARRAY;
  static constexpr int64_t kMin = integerMin<T>();
  static constexpr int64_t kMax = integerMax<T>();
  using Stored = int64_t;
  static int64_t toStored(const std::string& name, T value) {
    if constexpr (std::is_unsigned_v<T> && sizeof(T) >= sizeof(int64_t)) {
      if (value > static_cast<T>(kMax)) throwDoesNotFit(name, std::to_string(value), kMin, kMax);
    }
    return static_cast<int64_t>(value);
  }
  static T fromStored(const std::string& name, int64_t value) {
    if (value < kMin || value > kMax) throwDoesNotFit(name, std::to_string(value), kMin, kMax);
    return static_cast<T>(value);
  }
};

/// float and double are stored as double.
template <class T>
struct ScalarTraits<T, std::enable_if_t<std::is_floating_point_v<T>>> {
  static constexpr bool kSupported = true;
  static constexpr ParameterType kType = ParameterType::DOUBLE;
  static constexpr ParameterType kArrayType = ParameterType::DOUBLE_ARRAY;
  static constexpr int64_t kMin = std::numeric_limits<int64_t>::min();
  static constexpr int64_t kMax = std::numeric_limits<int64_t>::max();
  using Stored = double;
  static double toStored(const std::string& /*name*/, T value) { return value; }
  static T fromStored(const std::string& /*name*/, double value) { return static_cast<T>(value); }
};

/// std::string is stored as is.
template <>
struct ScalarTraits<std::string> {
  static constexpr bool kSupported = true;
  static constexpr ParameterType kType = ParameterType::STRING;
  static constexpr ParameterType kArrayType = ParameterType::STRING_ARRAY;
  static constexpr int64_t kMin = std::numeric_limits<int64_t>::min();
  static constexpr int64_t kMax = std::numeric_limits<int64_t>::max();
  using Stored = std::string;
  static std::string toStored(const std::string& /*name*/, const std::string& v) { return v; }
  static std::string fromStored(const std::string& /*name*/, const std::string& v) { return v; }
};

/// Converts a C++ parameter type T (scalar or std::vector of scalar) to and from ParameterValue.
template <class T, class Enable = void>
struct ParameterTraits {
  static constexpr bool kSupported = false;
};

/// Scalars.
template <class T>
struct ParameterTraits<T, std::enable_if_t<ScalarTraits<T>::kSupported>> {
  using Scalar = ScalarTraits<T>;
  static constexpr bool kSupported = true;
  static constexpr ParameterType kType = Scalar::kType;
  static ParameterValue toValue(const std::string& name, const T& value) {
    return ParameterValue(std::in_place_type<typename Scalar::Stored>,
                          Scalar::toStored(name, value));
  }
  static T fromValue(const std::string& name, const ParameterValue& value) {
    return Scalar::fromStored(name, std::get<typename Scalar::Stored>(value));
  }
};

/// std::vector of scalars.
template <class T>
struct ParameterTraits<std::vector<T>, std::enable_if_t<ScalarTraits<T>::kSupported>> {
  using Scalar = ScalarTraits<T>;
  using StoredVector = std::vector<typename Scalar::Stored>;
  static constexpr bool kSupported = true;
  static constexpr ParameterType kType = Scalar::kArrayType;
  static ParameterValue toValue(const std::string& name, const std::vector<T>& value) {
    StoredVector stored;
    stored.reserve(value.size());
    for (const auto& element : value) stored.push_back(Scalar::toStored(name, element));
    return ParameterValue(std::in_place_type<StoredVector>, std::move(stored));
  }
  static std::vector<T> fromValue(const std::string& name, const ParameterValue& value) {
    std::vector<T> result;
    const auto& stored = std::get<StoredVector>(value);
    result.reserve(stored.size());
    for (const auto& element : stored) result.push_back(Scalar::fromStored(name, element));
    return result;
  }
};

}  // namespace detail

/// The declared parameters of one node, with the overrides loaded for it from YAML and the
/// command line. See the file comment for format, precedence and conversion rules.
class Parameters {
 public:
  /// Outcome of a runtime set(); `reason` names the parameter and value when !ok.
  struct SetResult {
    bool ok = false;     // true if the value was accepted
    std::string reason;  // why it was rejected; empty when ok
  };

  /// Validation hook run before set() accepts a value; return {false, "why"} to veto.
  using Callback = std::function<SetResult(const std::string& name, const ParameterValue& value)>;

  /// `node_name` selects the section of parameter files that applies to this node.
  explicit Parameters(std::string node_name);
  ~Parameters();
  // Not copyable: owns mutexes and registered callbacks.
  Parameters(const Parameters&) = delete;
  Parameters& operator=(const Parameters&) = delete;

  /// Loads a parameter file; throws ParameterError("<path>: ...") if unreadable or malformed
  /// ("<path>:<line>:<col>: malformed YAML: ...").
  void loadFile(const std::string& path);

  /// Loads parameter-file text; `source_name` (usually a path) prefixes every error message.
  /// All-or-nothing: on error nothing from `text` is kept.
  void loadYaml(const std::string& text, const std::string& source_name);

  /// Adds a command-line override "name:=value"; value is a YAML scalar or flow sequence
  /// ("[1, 2]"). Beats every file. Throws ParameterError on a malformed assignment.
  void setOverride(const std::string& assignment,
                   const std::string& source_name = kCommandLineSource);

  /// Declares parameter `name` of type T (bool, an integral type, float/double, std::string or
  /// std::vector of those) and returns its value: the highest-precedence override, or
  /// `default_value`. Throws ParameterError if the override or default violates the type or
  /// descriptor, if the descriptor is inconsistent, or if `name` was declared with another type.
  /// Redeclaring with the same type returns the current value and keeps the first descriptor.
  template <class T>
  T declare(const std::string& name, const T& default_value,
            const ParameterDescriptor& descriptor = {}) {
    using Traits = detail::ParameterTraits<T>;
    static_assert(Traits::kSupported,
                  "parameter types: bool, integral, float/double, std::string, std::vector of "
                  "those");
    const ParameterValue value =
        declareValue(name, Traits::toValue(name, default_value), descriptor,
                     detail::ScalarTraits<typename detail::Element<T>::type>::kMin,
                     detail::ScalarTraits<typename detail::Element<T>::type>::kMax);
    return Traits::fromValue(name, value);
  }

  /// Declares a string parameter from a string literal default.
  std::string declare(const std::string& name, const char* default_value,
                      const ParameterDescriptor& descriptor = {});

  /// Current value of declared parameter `name` as T; throws ParameterError if undeclared, if T
  /// is not the declared type (integral types are interchangeable when the value fits).
  template <class T>
  T get(const std::string& name) const {
    using Traits = detail::ParameterTraits<T>;
    static_assert(Traits::kSupported,
                  "parameter types: bool, integral, float/double, std::string, std::vector of "
                  "those");
    const ParameterValue value = getValue(name);
    if (typeOf(value) != Traits::kType) detail::throwWrongType(name, typeOf(value), Traits::kType);
    return Traits::fromValue(name, value);
  }

  /// Current value of declared parameter `name`; throws ParameterError if undeclared.
  ParameterValue getValue(const std::string& name) const;

  /// Declared type of `name`; throws ParameterError if undeclared.
  ParameterType type(const std::string& name) const;

  /// True if `name` has been declared.
  bool has(const std::string& name) const;

  /// Declared parameter names, in declaration order.
  std::vector<std::string> names() const;

  /// Changes a declared parameter at runtime after checking type, descriptor, read_only and the
  /// onSet callbacks. An integer (array) is accepted for a double (array) parameter.
  SetResult set(const std::string& name, const ParameterValue& value);

  /// Changes a declared string parameter from a literal (avoids the const char* -> bool trap).
  SetResult set(const std::string& name, const char* value);

  /// Like set(), with the value given as YAML text converted by the file rules ("2.5", "[a, b]").
  SetResult setFromYaml(const std::string& name, const std::string& yaml_value);

  /// Registers a hook run (in registration order) before set() accepts a value; may veto.
  /// Not run for declare().
  void onSet(Callback callback);

  /// Node-specific and command-line overrides that no declaration used, each as
  /// "'<name>' from <source>" plus " (did you mean '<declared>'?)" when a declared name is close.
  /// Wildcard sections are not reported (they legitimately set parameters other nodes declare).
  std::vector<std::string> unusedOverrides() const;

  /// YAML map of all declared parameters in declaration order, each with type, value, unit,
  /// min/max, choices, read_only, description and source of the value (for --help and docs).
  std::string describe() const;

  /// Name of the node whose parameters these are.
  std::string node_name() const;

 private:
  /// Non-template part of declare(); `int_min`/`int_max` are the C++ integer type's range.
  ParameterValue declareValue(const std::string& name, ParameterValue default_value,
                              const ParameterDescriptor& descriptor, int64_t int_min,
                              int64_t int_max);

  struct Impl;
  std::unique_ptr<Impl> impl_;  // state and mutexes; keeps yaml-cpp out of this header
};

}  // namespace auv::interfaces
