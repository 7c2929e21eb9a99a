// Fuzz harness: component parameter files as `auv run ... --params FILE` reads them
// (Parameters::loadFile -> loadYaml), then the declarations a component makes (every type, with
// ranges and choices), the report of unused overrides and describe(); also the text of a
// `-p name:=value` override and of a runtime set (setOverride, setFromYaml), converted by the
// same rules. A clear error is a ParameterError naming the file and the parameter; anything else
// (a crash, a sanitizer report, another exception) is a bug.
#include <cstdint>
#include <string>
#include <vector>

#include "auv/interfaces/parameters.h"

using auv::interfaces::ParameterDescriptor;
using auv::interfaces::ParameterError;
using auv::interfaces::Parameters;

namespace {

ParameterDescriptor range(double min, double max) {
  ParameterDescriptor d;
  d.min = min;
  d.max = max;
  return d;
}

// Declares a parameter of every type, under the names the seeds use; each declaration may
// refuse the file's value with a ParameterError.
template <class T>
void declare(Parameters& p, const std::string& name, const T& value,
             const ParameterDescriptor& descriptor = {}) {
  try {
    p.declare<T>(name, value, descriptor);
  } catch (const ParameterError&) {
  }
}

void declareAll(Parameters& p) {
  ParameterDescriptor modes;
  modes.choices = {"fast", "slow", "survey"};
  ParameterDescriptor exclusive = range(0.0, 1.0);
  exclusive.min_exclusive = true;
  exclusive.max_exclusive = true;
  declare(p, "use_sim_time", false);
  declare(p, "enabled", true);
  declare<int>(p, "retries", 3, range(0, 10));
  declare<int64_t>(p, "big", 0);
  declare<uint8_t>(p, "level", 1);
  declare<uint32_t>(p, "mask", 0u);
  declare(p, "rate", 10.0, range(0.1, 100.0));
  declare(p, "ratio", 0.5, exclusive);
  declare<float>(p, "gain", 1.0f);
  declare<std::string>(p, "mode", "fast", modes);
  declare<std::string>(p, "name", "");
  declare(p, "planner.range", 2.0);
  declare(p, "flags", std::vector<bool>{});
  declare(p, "ids", std::vector<int>{});
  declare(p, "weights", std::vector<double>{0.5}, range(0.0, 1.0));
  declare(p, "frames", std::vector<std::string>{});
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  {
    Parameters p("planner");
    try {
      p.loadYaml(input, "fuzz_params.yaml");
    } catch (const ParameterError&) {
      return 0;
    }
    declareAll(p);
    p.unusedOverrides();
    p.describe();
    p.setFromYaml("weights", input);  // a runtime set: the result says whether it was taken
  }
  {
    Parameters p("planner");
    try {
      p.setOverride(input);
      declareAll(p);
    } catch (const ParameterError&) {
    }
  }
  return 0;
}

/// Parameter files as the file comment of parameters.h documents them: node and wildcard
/// sections, nested names, ROS 2 files, every type; and one with every declared parameter set
/// from its value's own text (toString, the format of messages and `auv param get`).
std::vector<std::string> auvFuzzSeeds() {
  std::vector<std::string> seeds = {
      "/**:\n  use_sim_time: false\nplanner:\n  mode: fast\n  planner:\n    range: 2.0\n"
      "  weights: [0.5, 0.25]\n",
      "/planner:\n  ros__parameters:\n    rate: 2.5\n    retries: 7\n",
      "\"*\":\n  enabled: false\nother_node:\n  rate: 1\nplanner:\n  big: "
      "-9223372036854775808\n  mask: 0xff\n  level: 0o17\n  gain: .inf\n  ratio: 1e-3\n"
      "  name: \"0042\"\n  flags: [true, false, True]\n  ids: [1, -2, 3]\n  frames: [base_link, "
      "\"camera\"]\n",
      "planner:\n  ids: []\n  weights:\n    - 0.5\n    - 1\n",
  };
  Parameters defaults("planner");
  declareAll(defaults);
  std::string all = "planner:\n";
  for (const std::string& name : defaults.names()) {
    all += "  " + name + ": " + auv::interfaces::toString(defaults.getValue(name)) + "\n";
  }
  seeds.push_back(all);
  return seeds;
}
