#pragma once
// Declares the fields of an options table (auv/config/option_table.h) as a component's
// parameters: the descriptor — meaning, unit, range with its open or closed ends, choices — is
// the table's, so `auv run <component> --help` shows exactly what Options::check() accepts.

#include <string>
#include <type_traits>
#include <variant>

#include "auv/config/option_table.h"
#include "auv/interfaces/parameters.h"

namespace auv::interfaces {

/// The descriptor of one table entry.
template <class Options>
ParameterDescriptor describeOption(const config::Option<Options>& option, bool read_only) {
  ParameterDescriptor descriptor;
  descriptor.description = option.description;
  descriptor.unit = option.unit;
  descriptor.min = option.range.min;
  descriptor.max = option.range.max;
  descriptor.min_exclusive = option.range.min_exclusive;
  descriptor.max_exclusive = option.range.max_exclusive;
  descriptor.choices = option.choices;
  descriptor.read_only = read_only;
  return descriptor;
}

/// Declares `<prefix><name>` for every field of `table` with the field's current value as the
/// default and the field's type (double, integer, bool, string), and stores the value the
/// parameters give (file, -p, default) back into `options`. Throws ParameterError naming the
/// parameter for a value outside its range or choices.
template <class Options>
void declareOptions(Parameters& parameters, const std::string& prefix,
                    const config::OptionTable<Options>& table, Options& options, bool read_only) {
  for (const config::Option<Options>& option : table) {
    const ParameterDescriptor descriptor = describeOption(option, read_only);
    std::visit(
        [&](auto field) {
          using T = std::remove_reference_t<decltype(options.*field)>;
          options.*field = parameters.declare<T>(prefix + option.name, options.*field, descriptor);
        },
        option.field);
  }
}

}  // namespace auv::interfaces
