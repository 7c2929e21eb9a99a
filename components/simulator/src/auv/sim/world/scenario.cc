#include "auv/sim/world/scenario.h"

#include <cmath>
#include <filesystem>
#include <sstream>
#include <system_error>

namespace auv::sim {
namespace {
namespace fs = std::filesystem;
constexpr double kDeg = M_PI / 180.0;

std::string number(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

// The `mission:` section: the band must lie inside the water column of this world.
void readMissionPlanning(const YamlSection& section, double seabed_depth, MissionPlanning& m) {
  section.rejectUnknownKeys({"fixed_depth", "min_depth", "max_depth", "min_altitude"});
  section.read("fixed_depth", m.fixed_depth);
  section.read("min_depth", m.min_depth);
  section.read("max_depth", m.max_depth);
  section.read("min_altitude", m.min_altitude);
  if (section.has("min_depth") != section.has("max_depth"))
    section.fail(section.has("min_depth") ? "max_depth" : "min_depth",
                 "missing: a depth band needs both min_depth and max_depth (m)");
  if (!(m.min_altitude >= 0.0)) section.fail("min_altitude", "must be >= 0 (m above the seabed)");
  if (!section.has("min_depth")) return;
  if (!(m.min_depth >= 0.0) || m.min_depth > seabed_depth)
    section.fail("min_depth", "must be inside the water column [0, " + number(seabed_depth) +
                                  "] m (world.seabed_depth)");
  if (!(m.max_depth >= 0.0) || m.max_depth > seabed_depth)
    section.fail("max_depth", "must be inside the water column [0, " + number(seabed_depth) +
                                  "] m (world.seabed_depth)");
  if (!(m.min_depth < m.max_depth))
    section.fail("max_depth", "must be greater than min_depth (" + number(m.min_depth) +
                                  " m), got " + number(m.max_depth));
}
}  // namespace

WaterOptics WaterOptics::fromVisibility(double visibility_m) {
  if (!(visibility_m > 0) || !std::isfinite(visibility_m)) {
    throw ConfigError("water visibility must be a positive number of metres");
  }
  // Koschmieder: contrast falls to 2 % at the visibility distance for the least attenuated
  // (green) channel. Coastal water ratios: red ~3.7x green, blue ~1.2x; backscatter slightly
  // weaker than attenuation; the veiling light is the blue-green of the water column.
  const double green = 3.912 / visibility_m;
  WaterOptics w;
  w.attenuation = Eigen::Vector3d(3.7, 1.0, 1.2) * green;
  w.backscatter = Eigen::Vector3d(3.0, 0.9, 1.0) * green;
  w.veiling_light = Eigen::Vector3d(0.03, 0.22, 0.26);
  w.visibility = visibility_m;
  return w;
}

void WaterOptics::check(const std::string& where) const {
  for (int c = 0; c < 3; ++c) {
    if (!std::isfinite(attenuation[c]) || attenuation[c] < 0) {
      throw ConfigError(where + ".attenuation: must be finite and >= 0 (1/m)");
    }
    if (!std::isfinite(backscatter[c]) || backscatter[c] < 0) {
      throw ConfigError(where + ".backscatter: must be finite and >= 0 (1/m)");
    }
    if (!std::isfinite(veiling_light[c]) || veiling_light[c] < 0 || veiling_light[c] > 1) {
      throw ConfigError(where + ".veiling_light: must be in [0, 1] (linear RGB)");
    }
  }
}

Eigen::Affine3f Scenario::meshToWorld() const {
  // Mesh frames are usually "up" frames; NED points down. z-up: (x, y, z) -> (x, -y, -z);
  // y-up (x right, z towards the viewer): (x, y, z) -> (x, z, -y). Both are rotations.
  Eigen::Matrix3f up_to_ned;
  if (up_axis == "y") {
    up_to_ned << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  } else {
    up_to_ned << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  }
  Eigen::Affine3f T = Eigen::Affine3f::Identity();
  T.translate(origin.cast<float>());
  T.rotate(Eigen::AngleAxisf(static_cast<float>(yaw_deg * kDeg), Eigen::Vector3f::UnitZ()));
  T.linear() = T.linear() * up_to_ned * static_cast<float>(scale);
  return T;
}

Scenario loadScenario(const std::string& path) {
  Scenario s;
  s.file = path;
  s.root = loadYamlFile(path);
  const YamlSection& root = s.root;
  root.rejectUnknownKeys({"name", "description", "world", "water", "vehicle", "navigation", "sonar",
                          "multibeam", "dvl_beams", "cameras", "lighting", "queries", "simulation",
                          "mission", "changes"});
  s.name = fs::path(path).stem().string();
  root.read("name", s.name);
  root.read("description", s.description);

  const YamlSection world = root.child("world");
  world.rejectUnknownKeys({"mesh", "up_axis", "origin", "yaw_deg", "scale", "default_color",
                           "seabed_depth", "surface_detail"});
  if (!world.has("mesh")) world.fail("mesh", "missing: the world's mesh file (.ply or .obj)");
  std::string mesh;
  world.read("mesh", mesh);
  const fs::path mesh_path = fs::path(mesh).is_absolute()
                                 ? fs::path(mesh)
                                 : fs::absolute(fs::path(path).parent_path() / mesh);
  s.mesh_path = mesh_path.lexically_normal().string();
  std::error_code error;  // a name the file system refuses (too long) is bad input too
  if (!fs::is_regular_file(s.mesh_path, error)) {
    const bool missing = !error || error == std::errc::no_such_file_or_directory ||
                         error == std::errc::not_a_directory;
    world.fail("mesh",
               missing ? "no such file: " + s.mesh_path : s.mesh_path + ": " + error.message());
  }
  world.read("up_axis", s.up_axis);
  if (s.up_axis != "z" && s.up_axis != "y")
    world.fail("up_axis", "expected z or y, got " + s.up_axis);
  world.read("origin", s.origin);
  world.read("yaw_deg", s.yaw_deg, -360.0, 360.0);
  world.read("scale", s.scale, 1e-6, 1e6);
  if (world.has("default_color")) {
    Eigen::Vector3d c;
    world.read("default_color", c, 0.0, 1.0);
    s.default_color = c.cast<float>();
  }
  world.read("seabed_depth", s.seabed_depth, 0.0, 12000.0);
  const YamlSection detail = world.child("surface_detail");
  detail.rejectUnknownKeys({"amplitude", "tile_size", "seed"});
  if (world.has("surface_detail")) s.surface_detail.amplitude = 0.5;  // present = on
  detail.read("amplitude", s.surface_detail.amplitude, 0.0, 2.0);
  detail.read("tile_size", s.surface_detail.tile_size, 0.01, 100.0);
  int detail_seed = 1;
  detail.read("seed", detail_seed, 0);
  s.surface_detail.seed = detail_seed;

  const YamlSection water = root.child("water");
  water.rejectUnknownKeys({"visibility", "attenuation", "backscatter", "veiling_light"});
  if (water.has("visibility")) {
    double visibility = 0;
    water.read("visibility", visibility, 0.1, 1000.0);
    s.water = WaterOptics::fromVisibility(visibility);
  }
  water.read("attenuation", s.water.attenuation, 0.0, 100.0);
  water.read("backscatter", s.water.backscatter, 0.0, 100.0);
  water.read("veiling_light", s.water.veiling_light, 0.0, 1.0);
  s.water.check(path + ": water");

  const YamlSection start = root.child("vehicle").child("start");
  start.rejectUnknownKeys({"position", "yaw_deg"});
  start.read("position", s.start_position);
  if (s.start_position.z() < 0) start.fail("position", "depth (z) must be >= 0 (NED)");
  double start_yaw_deg = 0;
  start.read("yaw_deg", start_yaw_deg, -360.0, 360.0);
  s.start_yaw = start_yaw_deg * kDeg;

  for (const YamlSection& q : root.childList("queries")) {
    q.rejectUnknownKeys({"name", "goal", "tolerance"});
    MissionQuery query;
    query.name = "query" + std::to_string(s.queries.size() + 1);
    q.read("name", query.name);
    if (!q.has("goal")) q.fail("goal", "missing: the query's goal [x, y, z] (m NED)");
    q.read("goal", query.goal);
    if (query.goal.z() < 0) q.fail("goal", "depth (z) must be >= 0 (NED)");
    q.read("tolerance", query.tolerance, 0.01, 1000.0);
    s.queries.push_back(query);
  }
  readMissionPlanning(root.child("mission"), s.seabed_depth, s.mission);
  s.changes = readSiteChanges(root);
  s.later_visit = root.has("changes");
  return s;
}

Mesh loadWorldMesh(const Scenario& scenario, MeshReport* report,
                   std::vector<AppliedChange>* applied) {
  Mesh mesh = loadWorldMeshBeforeChanges(scenario, report);
  if (scenario.changes.empty()) return mesh;
  std::vector<AppliedChange> done = applySiteChanges(mesh, scenario.changes, scenario.file);
  MeshReport r = validateMesh(mesh);
  if (report) {
    r.removed_degenerate += report->removed_degenerate;
    *report = r;
  }
  if (applied) *applied = std::move(done);
  return mesh;
}

Mesh loadWorldMeshBeforeChanges(const Scenario& scenario, MeshReport* report) {
  Mesh mesh = loadMesh(scenario.mesh_path);
  if (!mesh.hasTexture() && !mesh.hasVertexColors() && scenario.default_color) {
    mesh.vertex_colors.assign(mesh.vertices.size(), *scenario.default_color);
  }
  transformMesh(mesh, scenario.meshToWorld());
  MeshReport r = validateMesh(mesh);
  if (report) *report = r;
  return mesh;
}

}  // namespace auv::sim
