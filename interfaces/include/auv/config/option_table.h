#pragma once
// One declaration per option: an options struct lists each numeric field once — name, meaning,
// unit and range — and its check(), the component's parameter declarations and so
// `auv run <component> --help` all come from that list, so they cannot disagree (as a range
// (0.5, 1) in check() against [0.501, 0.999] in a descriptor did).
//
//   const config::OptionTable<Options>& Options::table() {
//     static const config::OptionTable<Options> kTable = {
//         {"prob_hit", &Options::prob_hit, "occupancy probability of a cell with a return", "",
//          config::Range::open(0.5, 1.0)}, ...};
//     return kTable;
//   }
//   void Options::check() const { config::checkOptions(*this, table()); ... }
//   // in the component: interfaces::declareOptions(node.parameters(), "", table, options);
//
// Cross-field rules (clamping_min <= prob_miss) stay in check(), after checkOptions().

#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
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

/// One numeric field of an options struct, declared once.
template <class Options>
struct NumberOption {
  const char* name;        ///< the field's and the parameter's name (under the prefix)
  double Options::*field;  ///< the member it binds
  const char* description;
  const char* unit;  ///< SI unit, "" when none
  Range range;
};

template <class Options>
using OptionTable = std::vector<NumberOption<Options>>;

/// Throws Error "<prefix><name>: expected a finite number<range>, got <value>" for the first
/// field of `table` out of its range. Error defaults to std::invalid_argument, the type every
/// options check() throws (exit code 2, errors.h).
template <class Error = std::invalid_argument, class Options>
void checkOptions(const Options& options, const OptionTable<Options>& table,
                  const std::string& prefix = "") {
  for (const NumberOption<Options>& option : table) {
    const double value = options.*option.field;
    if (option.range.contains(value)) continue;
    std::ostringstream message;
    message << prefix << option.name << ": expected a finite number" << option.range.text();
    if (*option.unit) message << " " << option.unit;
    message << ", got " << value;
    throw Error(message.str());
  }
}

}  // namespace auv::config
