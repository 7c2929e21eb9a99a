#pragma once
// Command-line arguments of the `auv bag` programs: the value after an option, parsed, or a
// std::invalid_argument naming the option (exit code 2).
#include <cstdint>
#include <stdexcept>
#include <string>

#include "auv/config/yaml_scalars.h"

namespace auv::bag {

class Arguments {
 public:
  Arguments(int argc, char** argv) : argc_(argc), argv_(argv) {}
  /// Moves to the next argument; false at the end.
  bool next() { return ++i_ < argc_; }
  std::string current() const { return argv_[i_]; }
  /// The following argument, the value of the current option.
  std::string value() {
    if (i_ + 1 >= argc_) throw std::invalid_argument(current() + ": needs a value");
    return argv_[++i_];
  }
  double number() {
    const std::string option = current(), text = value();
    const auto parsed = config::parseNumber(text);
    if (!parsed) throw std::invalid_argument(option + ": expected a number, got '" + text + "'");
    return *parsed;
  }
  int64_t integer() {
    const std::string option = current(), text = value();
    const auto parsed = config::parseInteger(text);
    if (!parsed) throw std::invalid_argument(option + ": expected an integer, got '" + text + "'");
    return *parsed;
  }
  /// The following arguments up to the next option ("-..."), e.g. a list of topics.
  template <class Out>
  void values(Out& out) {
    out.push_back(value());
    while (i_ + 1 < argc_ && argv_[i_ + 1][0] != '-') out.push_back(argv_[++i_]);
  }

 private:
  int argc_;
  char** argv_;
  int i_ = 0;
};

}  // namespace auv::bag
