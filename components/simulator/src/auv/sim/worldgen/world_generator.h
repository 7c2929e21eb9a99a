#pragma once
// Procedural worlds for the simulator: `breakwater` (paper Figs. 3-5: a row of 14.5 m x 12 m
// concrete blocks), `canyon` (Figs. 14-16 and section 4: two rocky formations forming a narrow
// canyon, navigated at 3 m depth) and `dead_end_bay` (a U-shaped bay whose direct route is a
// dead end), planned at fixed depth; and natural terrain that is not a vertical extrusion at
// the navigation depth, planned in 3-D: `boulder_field`, `arch` and `leaning_reef`. Each is one
// textured mesh plus a scenario file (start, queries, water, mission mode); the same name, seed
// and detail always give byte-identical files.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "auv/sim/common/yaml_section.h"
#include "auv/sim/world/mesh.h"
#include "auv/sim/world/scenario.h"

namespace auv::sim {

/// Bumped whenever generated output changes, so cached worlds of an older generator are rebuilt.
constexpr int kWorldGeneratorVersion = 5;

struct WorldGenOptions {
  uint64_t seed = 1;            ///< same seed, same world; another seed moves and reshapes the rock
  double detail = 1.0;          ///< scales triangle count and texel count (both ~ detail); 0.02..8
  int max_texture_size = 4096;  ///< px, the texture atlas's longest side (texels grow to fit)

  /// Throws ConfigError naming the field.
  void check() const;
  /// Reads `seed`, `detail`, `max_texture_size` strictly.
  static WorldGenOptions fromYaml(const YamlSection& section);
};

/// What a world was designed to be, in world NED (m): the tests check the mesh against it.
struct WorldLayout {
  std::vector<Eigen::AlignedBox3d> blocks;  ///< breakwater blocks
  /// Collision-free polylines at query depth, one per query, from where the previous query
  /// ends (the start for the first) to its goal: proof that every query can be solved.
  /// (In 3-D worlds the routes change depth, inside the mission's depth band.)
  std::vector<std::vector<Eigen::Vector3d>> routes;
  std::vector<Eigen::Vector3d> canyon_axis;  ///< canyon centre line at query depth, ~1 m steps
  double canyon_min_width = 0.0;             ///< m, designed range of the canyon's width at
  double canyon_max_width = 0.0;             ///< query depth along canyon_axis (roughness included)
  double query_depth = 0.0;                  ///< m
  /// boulder_field: designed top (NED) of every boulder whose top is meant to lie just below
  /// the start depth (a fixed-depth vehicle passes over it with little altitude).
  std::vector<Eigen::Vector3d> shallow_boulder_tops;
  std::vector<Eigen::Vector3d> tall_boulder_tops;  ///< boulder_field: tops above the start depth
  Eigen::Vector3d arch_under{0, 0, 0};    ///< arch: open water under the span, on a route (NED)
  Eigen::Vector3d arch_through{0, 0, 0};  ///< arch: unit horizontal direction of the passage
  /// leaning_reef: points at the surface (NED, z = 0) off the reef's face, and the unit
  /// horizontal direction from them towards the face.
  std::vector<Eigen::Vector3d> reef_stations;
  Eigen::Vector3d reef_towards{0, 0, 0};
};

struct WorldStats {
  size_t triangles = 0;
  int texture_width = 0;         ///< px
  int texture_height = 0;        ///< px
  double structure_texel = 0.0;  ///< m/texel on rock and concrete
  double seabed_texel = 0.0;     ///< m/texel on the seabed
  double seconds = 0.0;          ///< generation time (informative only)
};

struct GeneratedWorld {
  std::string name;
  std::string description;
  uint64_t seed = 0;
  double detail = 1.0;
  Mesh mesh;  ///< mesh frame: x north, y west, z up, z = 0 the sea surface (NED = (x, -y, -z))

  double seabed_depth = 10.0;               ///< m, flat seabed depth beyond the mesh
  double visibility = 5.0;                  ///< m, water visibility
  Eigen::Vector3d start_position{0, 0, 0};  ///< m NED
  double start_yaw_deg = 0.0;               ///< deg, 0 = north, towards the first goal
  std::vector<MissionQuery> queries;        ///< goals in NED, solved in order
  MissionPlanning mission;                  ///< the scenario's `mission:` section

  WorldLayout layout;
  WorldStats stats;
};

/// Names generateWorld() accepts, sorted.
std::vector<std::string> availableWorlds();
/// One line describing a known world ("" if unknown).
std::string worldSummary(const std::string& name);

/// Builds a world in memory. Throws ConfigError for an unknown name (listing the known ones)
/// or bad options.
GeneratedWorld generateWorld(const std::string& name, const WorldGenOptions& options = {});

/// The scenario file's text for `world` whose mesh is `mesh_file` (relative to the YAML).
std::string scenarioYaml(const GeneratedWorld& world, const std::string& mesh_file);

/// Writes <dir>/<name>.obj (+ .mtl and texture) and <dir>/<name>.yaml, creating `dir`. Files
/// are written under temporary names first and the YAML is moved into place last, so a reader
/// never sees a half-written world. Returns the YAML's path. Throws ConfigError on failure.
std::string writeWorld(const GeneratedWorld& world, const std::string& dir);

/// A scenario path for `name_or_scenario`: a .yaml/.yml path is returned as it is (it must
/// exist); a known world name gives <cache_dir>/<name>-<seed>/<name>.yaml (with "-d<detail>"
/// after the seed when detail != 1), generated first when missing or made by an older
/// generator. Safe when several processes ask at once. Throws ConfigError for anything else,
/// listing the known worlds.
std::string ensureWorld(const std::string& name_or_scenario, uint64_t seed,
                        const std::string& cache_dir, double detail = 1.0);

/// $AUV_WORLD_CACHE, else $XDG_CACHE_HOME/auv-inspect/worlds, else ~/.cache/auv-inspect/worlds.
std::string defaultWorldCache();

/// Mesh frame (x north, y west, z up) -> world NED, and back (the scenario maps meshes with
/// up_axis z this way).
inline Eigen::Vector3d meshToNed(const Eigen::Vector3d& p) { return {p.x(), -p.y(), -p.z()}; }
inline Eigen::Vector3d nedToMesh(const Eigen::Vector3d& p) { return {p.x(), -p.y(), -p.z()}; }

}  // namespace auv::sim
