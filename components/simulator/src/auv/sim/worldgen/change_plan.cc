#include "auv/sim/worldgen/change_plan.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <optional>
#include <random>
#include <sstream>

#include "auv/sim/raycast/ray_caster.h"

namespace auv::sim {
namespace {

namespace fs = std::filesystem;
constexpr double kDeg = M_PI / 180.0;

/// The first query's route by arc length.
class Route {
 public:
  explicit Route(const std::vector<Eigen::Vector3d>& points) : points_(points) {
    length_.push_back(0.0);
    for (size_t i = 1; i < points_.size(); ++i)
      length_.push_back(length_.back() + (points_[i] - points_[i - 1]).norm());
  }
  double length() const { return length_.back(); }
  /// Point and unit horizontal direction at arc length s.
  std::pair<Eigen::Vector3d, Eigen::Vector3d> at(double s) const {
    size_t i = 1;
    while (i + 1 < points_.size() && length_[i] < s) ++i;
    const double span = std::max(1e-9, length_[i] - length_[i - 1]);
    const double f = std::clamp((s - length_[i - 1]) / span, 0.0, 1.0);
    Eigen::Vector3d direction = points_[i] - points_[i - 1];
    direction.z() = 0.0;
    return {points_[i - 1] + f * (points_[i] - points_[i - 1]), direction.normalized()};
  }

 private:
  std::vector<Eigen::Vector3d> points_;
  std::vector<double> length_;
};

struct Site {
  Eigen::Vector3d point;
  bool floor = false;  ///< the surface faces up
};

class Planner {
 public:
  Planner(const GeneratedWorld& world, const ChangePlanOptions& options)
      : mesh_(worldMesh(world)),
        caster_(mesh_),
        route_(world.layout.routes.at(0)),
        random_(static_cast<uint32_t>(options.seed * 7919u + 1u)),
        options_(options) {}

  double uniform(double low, double high) {
    return std::uniform_real_distribution<double>(low, high)(random_);
  }

  /// A surface point filmed from the route's stretch, clear of the sites taken so far.
  std::optional<Site> site(double radius, bool floor_only) {
    for (int attempt = 0; attempt < 400; ++attempt) {
      const double s = uniform(options_.along_from, options_.along_to) * route_.length();
      const auto [origin, along] = route_.at(s);
      // Straight down turned sideways about the route, as the side cameras look.
      const Eigen::Vector3d side = Eigen::Vector3d::UnitZ().cross(along).normalized();
      const double tilt = uniform(-25.0, 25.0) * kDeg;
      const Eigen::Vector3d look =
          std::cos(tilt) * Eigen::Vector3d::UnitZ() + std::sin(tilt) * side;
      const RayHit hit = caster_.cast(origin.cast<float>(), look.cast<float>().normalized(), 10.0f);
      if (!hit.hit()) continue;
      const Eigen::Vector3d point = caster_.pointAt(hit).cast<double>();
      const bool floor = hit.normal.z() < -0.85f;  // NED: up is -z
      if (floor_only && !floor) continue;
      if (!clear(point, radius)) continue;
      return Site{point, floor};
    }
    return std::nullopt;
  }

  bool clear(const Eigen::Vector3d& point, double radius) const {
    for (const auto& [taken, taken_radius] : taken_)
      if ((taken - point).norm() < taken_radius + radius + 0.5) return false;
    return true;
  }
  void take(const Eigen::Vector3d& point, double radius) { taken_.emplace_back(point, radius); }

  /// A loose rock (boulder, fallen block) near the stretch: its centre and extent.
  std::optional<std::pair<Eigen::Vector3d, double>> looseRock() {
    for (int attempt = 0; attempt < 60; ++attempt) {
      const std::optional<Site> below = site(0.0, true);
      if (!below) return std::nullopt;
      for (const std::vector<int>& rock : looseRocksWithin(mesh_, below->point, 3.5)) {
        Eigen::Vector3d centre = Eigen::Vector3d::Zero();
        size_t n = 0;
        for (int t : rock)
          for (int k = 0; k < 3; ++k)
            centre += mesh_.vertices[mesh_.triangles[t][k]].cast<double>(), ++n;
        centre /= static_cast<double>(n);
        double extent = 0.0;
        for (int t : rock)
          for (int k = 0; k < 3; ++k)
            extent = std::max(
                extent, (mesh_.vertices[mesh_.triangles[t][k]].cast<double>() - centre).norm());
        if (extent <= 2.0 && clear(centre, extent)) return std::make_pair(centre, extent);
      }
    }
    return std::nullopt;
  }

  /// Depth of the surface under `xy` seen from `above_z` (NED), if any.
  std::optional<double> floorBelow(const Eigen::Vector3d& xy, double above_z) const {
    const RayHit hit =
        caster_.cast(Eigen::Vector3f(xy.x(), xy.y(), above_z), Eigen::Vector3f::UnitZ(), 15.0f);
    if (!hit.hit() || hit.normal.z() > -0.7f) return std::nullopt;
    return above_z + hit.distance;
  }

  const Mesh& mesh() const { return mesh_; }

 private:
  static Mesh worldMesh(const GeneratedWorld& world) {
    Mesh mesh = world.mesh;
    Eigen::Affine3f to_ned = Eigen::Affine3f::Identity();
    to_ned.linear() = Eigen::Vector3f(1.0f, -1.0f, -1.0f).asDiagonal();
    transformMesh(mesh, to_ned);
    return mesh;
  }

  Mesh mesh_;
  RayCaster caster_;
  Route route_;
  std::mt19937 random_;
  ChangePlanOptions options_;
  std::vector<std::pair<Eigen::Vector3d, double>> taken_;
};

std::string number(double value) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(3) << value;
  std::string text = out.str();
  while (text.back() == '0') text.pop_back();
  if (text.back() == '.') text.pop_back();
  return text == "-0" ? "0" : text;
}

std::string vec(const Eigen::Vector3d& v) {
  return "[" + number(v.x()) + ", " + number(v.y()) + ", " + number(v.z()) + "]";
}

}  // namespace

void ChangePlanOptions::check() const {
  if (!(along_from >= 0.0 && along_from < along_to && along_to <= 1.0))
    throw ConfigError(
        "--changes-along: expected 0 <= from < to <= 1 (fractions of the first "
        "query's route), got " +
        number(along_from) + "," + number(along_to));
}

std::vector<SiteChange> planSiteChanges(const GeneratedWorld& world,
                                        const ChangePlanOptions& options) {
  options.check();
  if (world.layout.routes.empty())
    throw ConfigError(world.name + ": the world has no reference route to place changes along");
  Planner planner(world, options);
  std::vector<SiteChange> changes;

  if (const std::optional<Site> s = planner.site(0.8, true)) {
    SiteChange block;
    block.name = "fallen_block";
    block.type = SiteChangeType::kAdd;
    block.center = s->point;
    block.size = {planner.uniform(0.9, 1.3), planner.uniform(0.6, 0.9), planner.uniform(0.45, 0.7)};
    block.yaw_deg = planner.uniform(-90.0, 90.0);
    block.seed = static_cast<int>(options.seed % 100000);
    planner.take(s->point, 0.8);
    changes.push_back(block);
  }
  if (const auto rock = planner.looseRock()) {
    SiteChange removed;
    removed.name = "removed_boulder";
    removed.type = SiteChangeType::kRemove;
    removed.center = rock->first;
    removed.radius = rock->second + 0.05;
    planner.take(rock->first, rock->second);
    changes.push_back(removed);
  }
  if (const auto rock = planner.looseRock()) {
    // Pushed clear of where it lay, along the floor: it lands at the floor's depth there (both
    // floors sampled just beside the rock, where nothing of it is in the way).
    const double extent = rock->second;
    for (int attempt = 0; attempt < 40; ++attempt) {
      const double angle = planner.uniform(0.0, 2.0 * M_PI);
      const Eigen::Vector3d direction(std::cos(angle), std::sin(angle), 0.0);
      const Eigen::Vector3d shift = planner.uniform(extent + 0.3, extent + 1.3) * direction;
      const Eigen::Vector3d target = rock->first + shift;
      const double above = rock->first.z() - extent - 0.3;
      const std::optional<double> old_floor =
          planner.floorBelow(rock->first + (extent + 0.2) * direction, above);
      const std::optional<double> new_floor = planner.floorBelow(target, above);
      if (!new_floor || !old_floor || !planner.clear(target, extent)) continue;
      SiteChange moved;
      moved.name = "moved_boulder";
      moved.type = SiteChangeType::kMove;
      moved.center = rock->first;
      moved.radius = extent + 0.05;
      moved.translation = shift + Eigen::Vector3d(0.0, 0.0, *new_floor - *old_floor);
      moved.yaw_deg = planner.uniform(-40.0, 40.0);
      planner.take(rock->first, extent);
      planner.take(target, extent);
      changes.push_back(moved);
      break;
    }
  }
  struct Patch {
    const char* name;
    SiteChangeType type;
    double radius, thickness;
    bool floor_only;
  };
  const Patch patches[] = {
      {"growth", SiteChangeType::kGrow, planner.uniform(1.0, 1.4), planner.uniform(0.15, 0.3),
       false},
      {"scour", SiteChangeType::kGrow, planner.uniform(0.9, 1.2), -planner.uniform(0.15, 0.25),
       true},
      {"bleached_patch", SiteChangeType::kAlbedo, planner.uniform(0.8, 1.1), 0.0, false}};
  for (const Patch& p : patches) {
    const std::optional<Site> s = planner.site(p.radius, p.floor_only);
    if (!s) continue;
    SiteChange patch;
    patch.name = p.name;
    patch.type = p.type;
    patch.center = s->point;
    patch.radius = p.radius;
    patch.thickness = p.thickness;
    planner.take(s->point, p.radius);
    changes.push_back(patch);
  }
  if (changes.empty())
    throw ConfigError(world.name +
                      ": no surface to place changes on under the first query's route");
  return changes;
}

std::string siteChangesYaml(const std::vector<SiteChange>& changes) {
  std::ostringstream out;
  out << "# What changed since the earlier visit (components/simulator/README.md, Sites that "
         "change).\nchanges:" << (changes.empty() ? " []  # none: a control visit" : "") << "\n";
  for (const SiteChange& c : changes) {
    out << "  - {name: " << c.name << ", type: " << toString(c.type);
    switch (c.type) {
      case SiteChangeType::kAdd:
        out << ", position: " << vec(c.center) << ", size: " << vec(c.size)
            << ", yaw_deg: " << number(c.yaw_deg) << ", seed: " << c.seed;
        break;
      case SiteChangeType::kRemove:
        out << ", center: " << vec(c.center) << ", radius: " << number(c.radius);
        break;
      case SiteChangeType::kMove:
        out << ", center: " << vec(c.center) << ", radius: " << number(c.radius)
            << ", translation: " << vec(c.translation) << ", yaw_deg: " << number(c.yaw_deg);
        break;
      case SiteChangeType::kGrow:
        out << ", center: " << vec(c.center) << ", radius: " << number(c.radius)
            << ", thickness: " << number(c.thickness);
        break;
      case SiteChangeType::kAlbedo:
        out << ", center: " << vec(c.center) << ", radius: " << number(c.radius)
            << ", color: " << vec(c.color) << ", strength: " << number(c.strength);
        break;
    }
    out << "}\n";
  }
  return out.str();
}

std::string writeEpochScenario(const GeneratedWorld& world, const std::vector<SiteChange>& changes,
                               const std::string& dir, int epoch) {
  std::string yaml = scenarioYaml(world, world.name + ".obj");
  const std::string name_line = "\nname: " + world.name + "\n";
  const std::string epoch_name = world.name + "_epoch" + std::to_string(epoch);
  const size_t at = yaml.find(name_line);
  if (at != std::string::npos) yaml.replace(at, name_line.size(), "\nname: " + epoch_name + "\n");
  yaml += siteChangesYaml(changes);
  const fs::path path = fs::path(dir) / (epoch_name + ".yaml");
  {
    std::ofstream out(path.string() + ".incomplete");
    out << yaml;
    if (!out) throw ConfigError(path.string() + ": cannot be written");
  }
  fs::rename(path.string() + ".incomplete", path);
  return path.string();
}

}  // namespace auv::sim
