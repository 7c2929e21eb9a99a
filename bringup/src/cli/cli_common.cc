#include "cli/cli_common.h"

#include <algorithm>

namespace auv::bringup {

Args::Args(std::vector<std::string> args, std::vector<std::string> flags,
           std::vector<std::string> options) {
  auto is = [](const std::vector<std::string>& list, const std::string& a) {
    return std::find(list.begin(), list.end(), a) != list.end();
  };
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "-h" || a == "--help") {
      help_ = true;
    } else if (is(flags, a)) {
      flags_set_.push_back(a);
    } else if (is(options, a)) {
      if (i + 1 >= args.size()) throw CliError("option " + a + " needs a value");
      options_set_.emplace_back(a, args[++i]);
    } else if (a.size() > 1 && a[0] == '-' && !(a[1] >= '0' && a[1] <= '9')) {
      throw CliError("unknown option '" + a + "'");
    } else {
      positional_.push_back(a);
    }
  }
}

bool Args::flag(const std::string& name) const {
  return std::find(flags_set_.begin(), flags_set_.end(), name) != flags_set_.end();
}

std::optional<std::string> Args::option(const std::string& name) const {
  std::optional<std::string> value;
  for (const auto& [k, v] : options_set_) {
    if (k == name) value = v;
  }
  return value;
}

double Args::number(const std::string& name, double fallback) const {
  const auto value = option(name);
  if (!value) return fallback;
  try {
    size_t used = 0;
    const double d = std::stod(*value, &used);
    if (used != value->size()) throw std::invalid_argument(*value);
    return d;
  } catch (const std::exception&) {
    throw CliError("option " + name + ": expected a number, got '" + *value + "'");
  }
}

const std::string& Args::at(size_t i, const std::string& what) const {
  if (i >= positional_.size()) throw CliError("missing " + what);
  return positional_[i];
}

std::string displayTopic(const std::string& topic) {
  return !topic.empty() && topic[0] == '/' ? topic : "/" + topic;
}

}  // namespace auv::bringup
