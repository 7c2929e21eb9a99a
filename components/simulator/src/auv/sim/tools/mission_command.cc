// `auv sim mission <world|scenario.yaml> [--seed N] [--out FILE]`: the world's inspection
// mission as a mission file for `auv mission start` (the simulator also writes it into every
// run folder).
#include <filesystem>
#include <fstream>
#include <iostream>

#include "auv/config/errors.h"
#include "auv/sim/tools/cli_args.h"
#include "auv/sim/tools/commands.h"
#include "auv/sim/world/mission_export.h"
#include "auv/sim/worldgen/world_generator.h"

namespace auv::sim {
namespace {
const char* kMissionUsage =
    "usage: auv sim mission <world|scenario.yaml> [--seed N] [--out FILE]\n"
    "Writes the world's inspection mission (its queries, the sampling bounds around the mesh,\n"
    "the visibility objective) as a mission file for `auv mission start`; stdout without --out.\n";
}  // namespace

int missionMain(const std::vector<std::string>& args) {
  std::string world, out;
  uint64_t seed = 1;
  try {
    for (size_t i = 0; i < args.size(); ++i) {
      const std::string& arg = args[i];
      if (arg == "-h" || arg == "--help") {
        std::cout << kMissionUsage;
        return 0;
      }
      auto value = [&]() -> const std::string& {
        if (i + 1 >= args.size()) throw UsageError(arg + ": needs a value");
        return args[++i];
      };
      if (arg == "--seed") {
        const double number = parseNumber(arg, value());
        if (number < 0 || number != static_cast<double>(static_cast<uint64_t>(number))) {
          throw UsageError("--seed: expected a whole number >= 0");
        }
        seed = static_cast<uint64_t>(number);
      } else if (arg == "--out") {
        out = value();
      } else if (!arg.empty() && arg[0] == '-') {
        throw UsageError("unknown option " + arg);
      } else if (world.empty()) {
        world = arg;
      } else {
        throw UsageError("unexpected argument '" + arg + "' (one world only)");
      }
    }
    if (world.empty()) throw UsageError("missing the world name or scenario file");
  } catch (const UsageError& e) {
    std::cerr << "auv sim mission: " << e.what() << "\n" << kMissionUsage;
    return 2;
  }
  try {
    const Scenario scenario = loadScenario(ensureWorld(world, seed, defaultWorldCache()));
    const std::string yaml = missionYaml(scenario, loadWorldMesh(scenario));
    if (out.empty()) {
      std::cout << yaml;
      return 0;
    }
    writeMissionFile(out, yaml);
    std::cerr << "mission of " << scenario.name << " written to " << out << "\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "auv sim mission: " << e.what() << "\n";
    return config::exitCodeFor(e);  // bad input 2, failures 1
  }
}

}  // namespace auv::sim
