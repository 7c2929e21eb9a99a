#include "auv/sim/worldgen/world_generator.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <map>
#include <random>
#include <sstream>
#include <system_error>

#include "auv/config/spelling.h"
#include "auv/sim/worldgen/world_builders.h"

namespace auv::sim {
namespace {

namespace fs = std::filesystem;

struct WorldEntry {
  std::function<GeneratedWorld(const WorldGenOptions&)> build;
  std::string summary;
};

const std::map<std::string, WorldEntry>& registry() {
  static const std::map<std::string, WorldEntry> worlds = {
      {"breakwater",
       {worldgen::buildBreakwater,
        "row of five 14.5 m x 12 m concrete blocks with 2-4 m gaps; cross the row (paper Figs. "
        "3-5)"}},
      {"canyon",
       {worldgen::buildCanyon,
        "two rocks forming a 4-8 m wide canyon at 3 m depth; traverse, go round, traverse again "
        "(paper section 4)"}},
      {"dead_end_bay",
       {worldgen::buildDeadEndBay,
        "U-shaped bay whose direct route is a dead end; escape through narrow side passages"}},
      {"boulder_field",
       {worldgen::buildBoulderField,
        "rounded boulders on a 10 m seabed, many tops just below 4 m, a few tall ones; cross "
        "over or around (3-D)"}},
      {"arch",
       {worldgen::buildArch,
        "rock arch (span from ~4.5 m depth to above the surface) with a wall beyond; pass "
        "under it at ~7 m, never surface under it (3-D)"}},
      {"leaning_reef",
       {worldgen::buildLeaningReef,
        "reef whose face leans out below 3 m (overhanging lip at ~6.5 m); work along it at "
        "depth (3-D)"}},
  };
  return worlds;
}

std::string joined(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& n : names) text += (text.empty() ? "" : ", ") + n;
  return text;
}

[[noreturn]] void unknownWorld(const std::string& name) {
  std::string message = "unknown world '" + name + "'";
  const std::string closest = config::closestMatch(name, availableWorlds());
  if (!closest.empty()) message += " (did you mean '" + closest + "'?)";
  message += "; known worlds: " + joined(availableWorlds()) + ", or a scenario .yaml file";
  throw ConfigError(message);
}

std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

std::string vec(const Eigen::Vector3d& v) {
  std::ostringstream out;
  // + 0.0 turns -0 (a mesh coordinate 0 mapped to NED) into 0.
  out << std::fixed << std::setprecision(3) << "[" << v.x() + 0.0 << ", " << v.y() + 0.0 << ", "
      << v.z() + 0.0 << "]";
  return out.str();
}

std::string header(const GeneratedWorld& world) {
  std::ostringstream out;
  out << "# auv-inspect worldgen v" << kWorldGeneratorVersion << ": " << world.name << ", seed "
      << world.seed << ", detail " << world.detail;
  return out.str();
}

// A name no other process uses: pid plus a per-process counter plus a random tag.
std::string uniqueTag() {
  static std::atomic<unsigned> counter{0};
  static const uint64_t salt = std::random_device{}();
  std::ostringstream out;
  out << ::getpid() << "-" << counter++ << "-" << std::hex << (salt & 0xffffff);
  return out.str();
}

void writeText(const fs::path& path, const std::string& text) {
  std::ofstream file(path, std::ios::binary);
  file << text;
  file.close();
  if (!file) throw ConfigError(path.string() + ": cannot write");
}

bool firstLineIs(const fs::path& path, const std::string& expected_prefix) {
  std::ifstream file(path);
  std::string line;
  return std::getline(file, line) && line.rfind(expected_prefix, 0) == 0;
}

}  // namespace

void WorldGenOptions::check() const {
  if (!(detail >= 0.02 && detail <= 8.0))
    throw ConfigError("worldgen.detail: expected a number in [0.02, 8], got " +
                      std::to_string(detail));
  if (max_texture_size < 256 || max_texture_size > 16384)
    throw ConfigError("worldgen.max_texture_size: expected 256..16384 px, got " +
                      std::to_string(max_texture_size));
}

WorldGenOptions WorldGenOptions::fromYaml(const YamlSection& section) {
  section.rejectUnknownKeys({"seed", "detail", "max_texture_size"});
  WorldGenOptions options;
  if (section.has("seed")) {
    try {
      options.seed = section.node()["seed"].as<uint64_t>();
    } catch (const YAML::Exception&) {
      section.fail("seed", "expected a whole number >= 0");
    }
  }
  section.read("detail", options.detail, 0.02, 8.0);
  section.read("max_texture_size", options.max_texture_size, 256, 16384);
  options.check();
  return options;
}

std::vector<std::string> availableWorlds() {
  std::vector<std::string> names;
  for (const auto& [name, entry] : registry()) names.push_back(name);
  return names;
}

std::string worldSummary(const std::string& name) {
  const auto it = registry().find(name);
  return it == registry().end() ? std::string() : it->second.summary;
}

GeneratedWorld generateWorld(const std::string& name, const WorldGenOptions& options) {
  options.check();
  const auto it = registry().find(name);
  if (it == registry().end()) unknownWorld(name);
  const auto t0 = std::chrono::steady_clock::now();
  GeneratedWorld world = it->second.build(options);
  world.stats.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return world;
}

std::string scenarioYaml(const GeneratedWorld& world, const std::string& mesh_file) {
  std::ostringstream out;
  out << header(world) << "\n"
      << "# Regenerate with: auv sim generate " << world.name << " --seed " << world.seed
      << " --detail " << world.detail << "\n"
      << "name: " << world.name << "\n"
      << "description: " << quoted(world.description) << "\n"
      << "world:\n"
      << "  mesh: " << mesh_file << "\n"
      << "  up_axis: z          # mesh frame: x north, y west, z up; z = 0 is the sea surface\n"
      << "  origin: [0, 0, 0]\n"
      << "  yaw_deg: 0\n"
      << "  scale: 1.0\n"
      << "  seabed_depth: " << world.seabed_depth << "\n"
      << "  surface_detail: {amplitude: 0.9, tile_size: 0.5, seed: " << world.seed
      << "}  # grain below the texture's 2 cm texels\n"
      << "water:\n"
      << "  visibility: " << world.visibility << "\n"
      << "vehicle:\n"
      << "  start: {position: " << vec(world.start_position) << ", yaw_deg: " << world.start_yaw_deg
      << "}\n"
      << "queries:\n";
  for (const MissionQuery& q : world.queries) {
    out << "  - {name: " << q.name << ", goal: " << vec(q.goal) << ", tolerance: " << q.tolerance
        << "}\n";
  }
  const MissionPlanning& m = world.mission;
  out << "# How the mission plans: fixed_depth true = one plane at the start depth (the paper's "
         "2-D mode,\n# worlds of vertical walls); false = 3-D inside [min_depth, max_depth] m, "
         "min_altitude m\n# above known seabed (natural terrain).\n"
      << "mission:\n  fixed_depth: " << (m.fixed_depth ? "true" : "false") << "\n";
  if (m.hasBand())
    out << "  min_depth: " << m.min_depth << "\n  max_depth: " << m.max_depth << "\n";
  if (m.min_altitude > 0.0) out << "  min_altitude: " << m.min_altitude << "\n";
  // 3-D planning needs 3-D sensing: rock below or above the vehicle's plane is invisible to the
  // profiling sonar (components/simulator/README.md, 3-D sensing).
  // The multibeam looks level with a 50 deg vertical fan (a 3-D imaging sonar's), not pitched
  // down: the default fan (15..35 deg down) never sees the underside of an arch, and a 3-D
  // path rising under one ran into it (arch, seed 2). Same rays per ping as the default.
  if (!m.fixed_depth)
    out << "# 3-D sensing: a level multibeam fan reaching 25 deg above and below the vehicle,\n"
        << "# and the DVL's four beams.\n"
        << "multibeam: {pitch_deg: 0, beams: 128, rows: 8, vertical_aperture_deg: 50}\n"
        << "dvl_beams: {}\n";
  return out.str();
}

std::string writeWorld(const GeneratedWorld& world, const std::string& dir) {
  if (world.name.empty() || world.mesh.triangles.empty())
    throw ConfigError("writeWorld: the world has no name or no mesh");
  std::error_code error;
  fs::create_directories(dir, error);
  if (error) throw ConfigError(dir + ": cannot create the folder (" + error.message() + ")");
  // Everything goes to a private folder first; files are then moved into `dir`, the YAML last.
  const fs::path staging = fs::path(dir) / ("." + world.name + ".tmp-" + uniqueTag());
  fs::create_directories(staging, error);
  if (error) throw ConfigError(staging.string() + ": cannot create (" + error.message() + ")");
  const std::string yaml_name = world.name + ".yaml";
  try {
    saveMesh(world.mesh, (staging / (world.name + ".obj")).string());
    writeText(staging / yaml_name, scenarioYaml(world, world.name + ".obj"));
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(staging)) files.push_back(entry.path());
    std::sort(files.begin(), files.end());
    for (const fs::path& file : files) {
      if (file.filename() != yaml_name) fs::rename(file, fs::path(dir) / file.filename());
    }
    fs::rename(staging / yaml_name, fs::path(dir) / yaml_name);
  } catch (const fs::filesystem_error& e) {
    fs::remove_all(staging, error);
    throw ConfigError(dir + ": cannot write the world (" + e.what() + ")");
  } catch (...) {
    fs::remove_all(staging, error);
    throw;
  }
  fs::remove_all(staging, error);
  return (fs::path(dir) / yaml_name).string();
}

std::string ensureWorld(const std::string& name_or_scenario, uint64_t seed,
                        const std::string& cache_dir, double detail) {
  const std::string ext = fs::path(name_or_scenario).extension().string();
  if (ext == ".yaml" || ext == ".yml") {
    if (!fs::is_regular_file(name_or_scenario))
      throw ConfigError(name_or_scenario + ": no such scenario file");
    return name_or_scenario;
  }
  if (registry().count(name_or_scenario) == 0) unknownWorld(name_or_scenario);

  const std::string& name = name_or_scenario;
  WorldGenOptions options;
  options.seed = seed;
  options.detail = detail;
  options.check();
  std::ostringstream key;
  key << name << "-" << seed;
  if (detail != 1.0) key << "-d" << detail;
  const fs::path folder = fs::path(cache_dir) / key.str();
  const fs::path yaml = folder / (name + ".yaml");
  const std::string current =
      "# auv-inspect worldgen v" + std::to_string(kWorldGeneratorVersion) + ":";
  if (fs::is_regular_file(yaml) && firstLineIs(yaml, current)) return yaml.string();

  // Generate into a private folder, then move the whole folder into place: other processes
  // see either no folder or a complete one.
  const GeneratedWorld world = generateWorld(name, options);
  const fs::path staging = fs::path(cache_dir) / ("." + key.str() + ".tmp-" + uniqueTag());
  writeWorld(world, staging.string());
  std::error_code error;
  if (fs::exists(folder)) {
    // A stale world (older generator, or incomplete): move it aside before replacing it.
    const fs::path old =
        fs::path(cache_dir) / ("." + folder.filename().string() + ".old-" + uniqueTag());
    fs::rename(folder, old, error);
    fs::remove_all(old, error);
  }
  fs::rename(staging, folder, error);
  if (error) {
    // Another process got there first; use its world if it is complete.
    fs::remove_all(staging, error);
    if (fs::is_regular_file(yaml) && firstLineIs(yaml, current)) return yaml.string();
    throw ConfigError(folder.string() + ": cannot store the generated world");
  }
  return yaml.string();
}

std::string defaultWorldCache() {
  if (const char* explicit_dir = std::getenv("AUV_WORLD_CACHE"); explicit_dir && *explicit_dir)
    return explicit_dir;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg)
    return (fs::path(xdg) / "auv-inspect" / "worlds").string();
  const char* home = std::getenv("HOME");
  return (fs::path(home && *home ? home : ".") / ".cache" / "auv-inspect" / "worlds").string();
}

}  // namespace auv::sim
