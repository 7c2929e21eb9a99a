#pragma once
// Argument helpers shared by the `auv sim` commands.

#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace auv::sim {

/// A bad command line: the command prints it with its usage and exits 2.
struct UsageError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

/// `text` as a finite number, or UsageError naming `option`.
inline double parseNumber(const std::string& option, const std::string& text) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(value)) {
    throw UsageError(option + ": expected a number, got '" + text + "'");
  }
  return value;
}

}  // namespace auv::sim
