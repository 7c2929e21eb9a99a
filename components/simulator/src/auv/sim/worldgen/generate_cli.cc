#include "auv/sim/worldgen/generate_cli.h"

#include <cerrno>
#include <cstdlib>
#include <iomanip>
#include <limits>
#include <sstream>

#include "auv/sim/worldgen/change_plan.h"
#include "auv/sim/worldgen/world_generator.h"

namespace auv::sim {
namespace {

constexpr const char* kPrefix = "auv sim generate: ";

void usage(std::ostream& out) {
  out << "usage: auv sim generate <world|all> [--seed N] [--out DIR] [--detail X]\n"
         "                        [--texture-size PX] [--epoch 2 [--changes-seed N]\n"
         "                        [--changes-along FROM,TO]]\n"
         "       auv sim generate --list\n\n"
         "Generates a procedural world: a textured mesh (<world>.obj, .mtl, texture .png) and a\n"
         "scenario file <world>.yaml (start, queries, water) that the simulator and\n"
         "`auv sim check` read. The same world, seed and detail always give the same files.\n\n"
         "worlds:\n";
  for (const std::string& name : availableWorlds())
    out << "  " << std::left << std::setw(14) << name << worldSummary(name) << "\n";
  out << "\noptions:\n"
         "  --seed N           random seed, a whole number >= 0 (default 1)\n"
         "  --out DIR          folder to write to, created if missing (default: .)\n"
         "  --detail X         scales triangles and texels, both ~X (default 1; 0.02..8)\n"
         "  --texture-size PX  the texture's longest side (default 4096; texels grow to fit)\n"
         "  --epoch 2          also write <world>_epoch2.yaml: a later visit of the same site\n"
         "                     with seeded changes (a fallen block, a removed and a moved\n"
         "                     boulder, growth, scour, a bleached patch) under the first\n"
         "                     query's route; render its run for ground_truth/changes.json\n"
         "  --changes-seed N   seed of the changes (default 1)\n"
         "  --changes-along F,T  the stretch of the first query's route they lie under, as\n"
         "                     fractions of its length (default 0.25,0.5)\n"
         "  --no-changes       --epoch 2 with `changes: []`: a later visit where nothing\n"
         "                     changed (a control: every change found in it is false)\n"
         "  --list             print the worlds and exit\n"
         "  -h, --help         print this help\n";
}

bool parseUnsigned(const std::string& text, uint64_t& value) {
  if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos) return false;
  errno = 0;
  char* end = nullptr;
  const unsigned long long parsed = std::strtoull(text.c_str(), &end, 10);
  if (errno != 0 || *end != '\0') return false;
  value = parsed;
  return true;
}

bool parseDouble(const std::string& text, double& value) {
  char* end = nullptr;
  errno = 0;
  value = std::strtod(text.c_str(), &end);
  return !text.empty() && errno == 0 && *end == '\0';
}

}  // namespace

int runGenerateCommand(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  WorldGenOptions options;
  std::string out_dir = ".";
  std::vector<std::string> worlds;
  int epoch = 1;
  ChangePlanOptions changes;
  bool no_changes = false;
  auto usageError = [&](const std::string& message) {
    err << kPrefix << message << " (see --help)\n";
    return 2;
  };
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    if (arg == "-h" || arg == "--help") {
      usage(out);
      return 0;
    }
    if (arg == "--list") {
      for (const std::string& name : availableWorlds())
        out << name << "  " << worldSummary(name) << "\n";
      return 0;
    }
    const bool takes_value = arg == "--seed" || arg == "--out" || arg == "--detail" ||
                             arg == "--texture-size" || arg == "--epoch" ||
                             arg == "--changes-seed" || arg == "--changes-along";
    if (takes_value) {
      if (i + 1 >= args.size()) return usageError(arg + " needs a value");
      const std::string& value = args[++i];
      if (arg == "--seed") {
        if (!parseUnsigned(value, options.seed))
          return usageError("--seed: expected a whole number >= 0, got '" + value + "'");
      } else if (arg == "--out") {
        out_dir = value;
      } else if (arg == "--epoch") {
        if (value != "1" && value != "2")
          return usageError(
              "--epoch: expected 1 (the site as generated) or 2 (a later visit "
              "with changes), got '" +
              value + "'");
        epoch = value == "2" ? 2 : 1;
      } else if (arg == "--changes-seed") {
        if (!parseUnsigned(value, changes.seed))
          return usageError("--changes-seed: expected a whole number >= 0, got '" + value + "'");
      } else if (arg == "--changes-along") {
        const size_t comma = value.find(',');
        if (comma == std::string::npos ||
            !parseDouble(value.substr(0, comma), changes.along_from) ||
            !parseDouble(value.substr(comma + 1), changes.along_to))
          return usageError("--changes-along: expected FROM,TO (fractions), got '" + value + "'");
        try {
          changes.check();
        } catch (const ConfigError& e) {
          return usageError(e.what());
        }
      } else if (arg == "--detail") {
        if (!parseDouble(value, options.detail) ||
            !(options.detail >= 0.02 && options.detail <= 8.0))
          return usageError("--detail: expected a number in [0.02, 8], got '" + value + "'");
      } else {
        uint64_t size = 0;
        if (!parseUnsigned(value, size) || size < 256 || size > 16384)
          return usageError("--texture-size: expected 256..16384 px, got '" + value + "'");
        options.max_texture_size = static_cast<int>(size);
      }
      continue;
    }
    if (arg == "--no-changes") {
      no_changes = true;
      continue;
    }
    if (!arg.empty() && arg[0] == '-') return usageError("unknown option '" + arg + "'");
    worlds.push_back(arg);
  }
  if (no_changes && epoch != 2) return usageError("--no-changes is for --epoch 2");
  if (worlds.empty())
    return usageError("which world? give one of " + [] {
      std::string names;
      for (const std::string& n : availableWorlds()) names += n + ", ";
      return names + "or all";
    }());
  if (worlds.size() > 1)
    return usageError("give one world (or all), got " + std::to_string(worlds.size()));
  std::vector<std::string> names = worlds[0] == "all" ? availableWorlds() : worlds;
  for (const std::string& name : names) {
    if (worldSummary(name).empty()) {
      try {
        generateWorld(name, options);  // throws the error with the suggestion
      } catch (const ConfigError& e) {
        return usageError(e.what());
      }
    }
  }

  for (const std::string& name : names) {
    try {
      const GeneratedWorld world = generateWorld(name, options);
      std::string yaml = writeWorld(world, out_dir);
      if (epoch == 2)
        yaml += " and " + writeEpochScenario(
                              world,
                              no_changes ? std::vector<SiteChange>{} : planSiteChanges(world, changes),
                              out_dir, 2);
      std::ostringstream line;
      line << std::fixed << std::setprecision(1) << name << ": " << world.stats.triangles
           << " triangles, texture " << world.stats.texture_width << "x"
           << world.stats.texture_height << " (" << world.stats.structure_texel * 100.0
           << " cm/texel on structures, " << world.stats.seabed_texel * 100.0
           << " cm on the seabed), seed " << options.seed << ", " << world.stats.seconds << " s -> "
           << yaml << "\n";
      out << line.str() << std::flush;
    } catch (const std::exception& e) {
      err << kPrefix << name << ": " << e.what() << "\n";
      return 1;
    }
  }
  return 0;
}

}  // namespace auv::sim
