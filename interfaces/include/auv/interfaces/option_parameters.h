#pragma once
// Declares the fields of an options table (auv/config/option_table.h) as a component's
// parameters: the descriptor — meaning, unit, range with its open or closed ends — is the
// table's, so `auv run <component> --help` shows exactly what Options::check() accepts.

#include <string>

#include "auv/config/option_table.h"
#include "auv/interfaces/parameters.h"

namespace auv::interfaces {

/// Declares `<prefix><name>` for every field of `table` with the field's current value as the
/// default, and stores the value the parameters give (file, -p, default) back into `options`.
/// Throws ParameterError naming the parameter for a value outside its range.
template <class Options>
void declareOptions(Parameters& parameters, const std::string& prefix,
                    const config::OptionTable<Options>& table, Options& options, bool read_only) {
  for (const config::NumberOption<Options>& option : table) {
    ParameterDescriptor descriptor;
    descriptor.description = option.description;
    descriptor.unit = option.unit;
    descriptor.min = option.range.min;
    descriptor.max = option.range.max;
    descriptor.min_exclusive = option.range.min_exclusive;
    descriptor.max_exclusive = option.range.max_exclusive;
    descriptor.read_only = read_only;
    options.*option.field =
        parameters.declare<double>(prefix + option.name, options.*option.field, descriptor);
  }
}

}  // namespace auv::interfaces
