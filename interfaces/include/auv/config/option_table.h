#pragma once
// One declaration per option: an options struct lists each field once — name, meaning, unit
// and the values it accepts (a range with open or closed ends for numbers, choices for strings)
// — and its check(), the component's parameter declarations and so
// `auv run <component> --help` all come from that list, so they cannot disagree (as a range
// (0.5, 1) in check() against [0.501, 0.999] in a descriptor did).
//
//   const config::OptionTable<Options>& Options::table() {
//     static const config::OptionTable<Options> kTable = {
//         {"prob_hit", &Options::prob_hit, "occupancy probability of a cell with a return", "",
//          config::Range::open(0.5, 1.0)},
//         {"queue_length", &Options::queue_length, "beams kept waiting", "beams",
//          config::Range::closed(0, 100000)},                           // an int64_t member
//         {"stop_at_occupied", &Options::stop_at_occupied, "..."},      // a bool member
//         {"objective", &Options::objective, "...", "", {}, {"visibility", "path_length"}}};
//     return kTable;
//   }
//   void Options::check() const { config::checkOptions(*this, table()); ... }
//   // in the component: interfaces::declareOptions(node.parameters(), "", table, options);
//
// A nested options struct has a table of its own, declared under a prefix ("pose_",
// "controller.model."). Cross-field rules (clamping_min <= prob_miss) stay in check(), after
// checkOptions().

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

namespace auv::config {

/// A numeric range; each end may be absent, inclusive or exclusive.
struct Range {
  std::optional<double> min;
  std::optional<double> max;
  bool min_exclusive = false;
  bool max_exclusive = false;

  static Range closed(double min, double max) { return {min, max, false, false}; }
  static Range open(double min, double max) { return {min, max, true, true}; }
  static Range atLeast(double min) { return {min, std::nullopt, false, false}; }
  static Range above(double min) { return {min, std::nullopt, true, false}; }
  /// (min, max]
  static Range aboveUpTo(double min, double max) { return {min, max, true, false}; }
  static Range any() { return {}; }

  /// True for a finite value inside the range.
  bool contains(double value) const {
    if (!std::isfinite(value)) return false;
    if (min && (min_exclusive ? value <= *min : value < *min)) return false;
    if (max && (max_exclusive ? value >= *max : value > *max)) return false;
    return true;
  }
  /// " in (0.5, 1)", " > 0", " >= 0", " <= 3", or "" for any finite number.
  std::string text() const {
    std::ostringstream out;
    out.precision(12);  // 16777216, not 1.67772e+07
    if (min && max) {
      out << " in " << (min_exclusive ? "(" : "[") << *min << ", " << *max
          << (max_exclusive ? ")" : "]");
    } else if (min) {
      out << (min_exclusive ? " > " : " >= ") << *min;
    } else if (max) {
      out << (max_exclusive ? " < " : " <= ") << *max;
    }
    return out.str();
  }
};

/// The member an option binds: a number (double, int, int64_t, uint32_t, size_t), a bool, a
/// string or a list of strings. Parameters of the integer kinds are declared as integers and keep
/// their C++ type's limits (a uint32_t refuses -1).
template <class Options>
using OptionField = std::variant<double Options::*, int Options::*, int64_t Options::*,
                                 uint32_t Options::*, uint64_t Options::*, bool Options::*,
                                 std::string Options::*, std::vector<std::string> Options::*>;

static_assert(std::is_same_v<std::size_t, uint64_t>, "size_t members bind as uint64_t");

/// One field of an options struct, declared once: its name, meaning, unit and the values it
/// accepts — a range for numbers, a list of choices for strings (empty: any string).
template <class Options>
struct Option {
  const char* name;            ///< the field's and the parameter's name (under the prefix)
  OptionField<Options> field;  ///< the member it binds
  std::string description;     ///< one line for `--help` and the docs
  const char* unit = "";       ///< SI unit, "" when none
  Range range;                 ///< numbers: the accepted values (default: any)
  /// strings (and each string of a list): the accepted values; empty: any
  std::vector<std::string> choices;

  /// The bound member of type T (std::bad_variant_access for another type).
  template <class T>
  T Options::*member() const {
    return std::get<T Options::*>(field);
  }
};

/// The name the first, numbers-only tables used.
template <class Options>
using NumberOption = Option<Options>;

template <class Options>
using OptionTable = std::vector<Option<Options>>;

namespace detail {

template <class T>
inline constexpr bool kIsNumber = std::is_arithmetic_v<T> && !std::is_same_v<T, bool>;

/// "one of a, b, c".
inline std::string choicesText(const std::vector<std::string>& choices) {
  std::string text = "one of ";
  for (size_t i = 0; i < choices.size(); ++i) text += (i ? ", " : "") + choices[i];
  return text;
}

/// The complaint about `value` of `option` (prefix included), or "" when it is accepted.
template <class Options, class T>
std::string complaint(const Option<Options>& option, const T& value, const std::string& prefix) {
  std::ostringstream message;
  message.precision(12);
  auto accepted = [&](const std::string& text) {
    return option.choices.empty() ||
           std::find(option.choices.begin(), option.choices.end(), text) != option.choices.end();
  };
  if constexpr (kIsNumber<T>) {
    if (option.range.contains(static_cast<double>(value))) return "";
    message << prefix << option.name << ": expected "
            << (std::is_floating_point_v<T> ? "a finite number" : "an integer")
            << option.range.text();
    if (*option.unit) message << " " << option.unit;
    message << ", got " << value;
  } else if constexpr (std::is_same_v<T, std::string>) {
    if (accepted(value)) return "";
    message << prefix << option.name << ": expected " << choicesText(option.choices) << ", got '"
            << value << "'";
  } else if constexpr (std::is_same_v<T, std::vector<std::string>>) {
    for (const std::string& element : value) {
      if (accepted(element)) continue;
      message << prefix << option.name << ": expected each " << choicesText(option.choices)
              << ", got '" << element << "'";
      break;
    }
  }
  return message.str();  // bool: every value is accepted
}

}  // namespace detail

/// Throws Error "<prefix><name>: expected a finite number<range>, got <value>" (integers:
/// "expected an integer<range>", strings: "expected one of a, b, got 'c'") for the first field
/// of `table` its declaration refuses. Error defaults to std::invalid_argument, the type every
/// options check() throws (exit code 2, errors.h).
template <class Error = std::invalid_argument, class Options>
void checkOptions(const Options& options, const OptionTable<Options>& table,
                  const std::string& prefix = "") {
  for (const Option<Options>& option : table) {
    const std::string message =
        std::visit([&](auto field) { return detail::complaint(option, options.*field, prefix); },
                   option.field);
    if (!message.empty()) throw Error(message);
  }
}

}  // namespace auv::config
