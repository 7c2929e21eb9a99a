#include "auv/sim/world/change_truth.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

#include "auv/sim/raycast/ray_caster.h"

namespace auv::sim {
namespace {

namespace fs = std::filesystem;

struct Sample {
  Eigen::Vector3f point;
  float distance;
};

/// Area-uniform samples of the triangles of `mesh` near the support, with their signed distance
/// to `other` (positive where the sample lies on the outer side of `other`'s nearest triangle),
/// kept where that distance is at least min_distance_m. `margin` widens the support (surfaces
/// just outside a block's bounding sphere still belong to it).
std::vector<Sample> standingOut(const Mesh& mesh, const RayCaster& other,
                                const ChangeSupport& support, const ChangeTruthOptions& options,
                                std::mt19937& random, float margin = 0.05f) {
  std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
  const Eigen::Vector3f centre = support.center.cast<float>();
  const float reach = static_cast<float>(support.radius) + margin;
  const float per_m2 = static_cast<float>(1.0 / (options.spacing_m * options.spacing_m));
  std::vector<Sample> samples;
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3f &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]],
                          &c = mesh.vertices[t[2]];
    if (((a + b + c) / 3.0f - centre).norm() > reach + (b - a).norm() + (c - a).norm()) continue;
    const float expected = 0.5f * (b - a).cross(c - a).norm() * per_m2;
    int count = static_cast<int>(expected);
    if (uniform(random) < expected - static_cast<float>(count)) ++count;
    for (int i = 0; i < count; ++i) {
      float u = uniform(random), v = uniform(random);
      if (u + v > 1.0f) u = 1.0f - u, v = 1.0f - v;
      const Eigen::Vector3f p = a + u * (b - a) + v * (c - a);
      if ((p - centre).norm() > reach) continue;
      Eigen::Vector3f closest;
      uint32_t triangle = 0;
      float distance = static_cast<float>(options.max_distance_m);
      if (other.closestPoint(p, distance, closest, triangle)) {
        const Eigen::Vector3i& o = other.mesh().triangles[triangle];
        const Eigen::Vector3f normal =
            (other.mesh().vertices[o[1]] - other.mesh().vertices[o[0]])
                .cross(other.mesh().vertices[o[2]] - other.mesh().vertices[o[0]]);
        distance = (p - closest).norm();
        if ((p - closest).dot(normal) < 0.0f) distance = -distance;
      }  // nothing within reach: far out of the other surface
      if (distance >= options.min_distance_m) samples.push_back({p, distance});
    }
  }
  return samples;
}

/// Volume between the two surfaces inside the support, by vertical columns cast downwards
/// from just above it: (gained, lost).
std::pair<double, double> columnVolumes(const RayCaster& before, const RayCaster& after,
                                        const ChangeSupport& support, double cell) {
  double gained = 0.0, lost = 0.0;
  const double r = support.radius;
  const float top = static_cast<float>(support.center.z() - r - 0.1);
  const float depth = static_cast<float>(2.0 * r + 0.2);
  const Eigen::Vector3f down(0.0f, 0.0f, 1.0f);
  for (double x = -r; x <= r; x += cell) {
    for (double y = -r; y <= r; y += cell) {
      if (x * x + y * y > r * r) continue;
      const Eigen::Vector3f origin(static_cast<float>(support.center.x() + x),
                                   static_cast<float>(support.center.y() + y), top);
      const RayHit b = before.cast(origin, down, depth), a = after.cast(origin, down, depth);
      // A column with no surface in one visit is measured down to the support's bottom.
      const double height = (b.hit() ? b.distance : depth) - (a.hit() ? a.distance : depth);
      (height > 0 ? gained : lost) += std::abs(height) * cell * cell;
    }
  }
  return {gained, lost};
}

ChangeTruthRegion summarise(const std::string& name, const AppliedChange& applied,
                            const std::vector<Sample>& samples, double spacing) {
  ChangeTruthRegion region;
  region.name = name;
  region.change = applied.change.name;
  region.type = applied.change.type;
  region.geometric = applied.change.type != SiteChangeType::kAlbedo;
  region.points = samples.size();
  region.area_m2 = static_cast<double>(samples.size()) * spacing * spacing;
  if (samples.empty()) {
    region.centroid = applied.supports.front().center;
    return region;
  }
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double distance_sum = 0.0;
  for (const Sample& s : samples) {
    sum += s.point.cast<double>();
    distance_sum += s.distance;
    if (std::abs(s.distance) > std::abs(region.max_distance_m)) region.max_distance_m = s.distance;
  }
  region.centroid = sum / static_cast<double>(samples.size());
  region.mean_distance_m = distance_sum / static_cast<double>(samples.size());
  for (const Sample& s : samples)
    region.radius_m = std::max(region.radius_m, (s.point.cast<double>() - region.centroid).norm());
  return region;
}

}  // namespace

ChangeTruth measureChangeTruth(const Mesh& before, const Mesh& after,
                               const std::vector<AppliedChange>& applied,
                               const ChangeTruthOptions& options) {
  const RayCaster before_caster(before), after_caster(after);
  std::mt19937 random(options.seed);
  ChangeTruth truth;
  auto add = [&](ChangeTruthRegion region, const std::vector<Sample>& samples) {
    const int index = static_cast<int>(truth.regions.size());
    for (const Sample& s : samples) {
      truth.points.push_back(s.point);
      truth.distances.push_back(s.distance);
      truth.region_of_point.push_back(index);
    }
    truth.regions.push_back(std::move(region));
  };
  for (const AppliedChange& change : applied) {
    const ChangeSupport& where = change.supports.front();
    if (change.change.type == SiteChangeType::kAlbedo) {
      // The colour changed, not the shape: the patch's samples, at distance 0.
      ChangeTruthOptions patch = options;
      patch.min_distance_m = -1e9;
      const ChangeSupport plateau{where.center, 0.7 * where.radius};
      std::vector<Sample> samples = standingOut(after, before_caster, plateau, patch, random, 0.0f);
      for (Sample& s : samples) s.distance = 0.0f;
      add(summarise(change.change.name, change, samples, options.spacing_m), samples);
      continue;
    }
    if (change.change.type == SiteChangeType::kMove) {
      std::vector<Sample> from =
          standingOut(before, after_caster, change.supports[0], options, random);
      for (Sample& s : from) s.distance = -s.distance;
      ChangeTruthRegion from_region =
          summarise(change.change.name + "/from", change, from, options.spacing_m);
      from_region.volume_lost_m3 =
          columnVolumes(before_caster, after_caster, change.supports[0], options.column_m).second;
      add(from_region, from);
      const std::vector<Sample> to =
          standingOut(after, before_caster, change.supports[1], options, random);
      ChangeTruthRegion to_region =
          summarise(change.change.name + "/to", change, to, options.spacing_m);
      to_region.volume_gained_m3 =
          columnVolumes(before_caster, after_caster, change.supports[1], options.column_m).first;
      add(to_region, to);
      continue;
    }
    std::vector<Sample> samples = standingOut(after, before_caster, where, options, random);
    std::vector<Sample> lost = standingOut(before, after_caster, where, options, random);
    for (Sample& s : lost) s.distance = -s.distance;
    samples.insert(samples.end(), lost.begin(), lost.end());
    ChangeTruthRegion region = summarise(change.change.name, change, samples, options.spacing_m);
    if (change.change.type == SiteChangeType::kGrow) {
      (change.displaced_volume_m3 > 0 ? region.volume_gained_m3 : region.volume_lost_m3) =
          std::abs(change.displaced_volume_m3);
    } else {
      std::tie(region.volume_gained_m3, region.volume_lost_m3) =
          columnVolumes(before_caster, after_caster, where, options.column_m);
    }
    add(region, samples);
  }
  return truth;
}

void writeChangeTruth(const ChangeTruth& truth, const std::string& dir,
                      const std::string& scenario_name, const ChangeTruthOptions& options) {
  fs::create_directories(dir);
  nlohmann::json regions = nlohmann::json::array();
  for (const ChangeTruthRegion& r : truth.regions) {
    regions.push_back({{"name", r.name},
                       {"change", r.change},
                       {"type", toString(r.type)},
                       {"geometric", r.geometric},
                       {"centroid", {r.centroid.x(), r.centroid.y(), r.centroid.z()}},
                       {"radius_m", r.radius_m},
                       {"area_m2", r.area_m2},
                       {"mean_distance_m", r.mean_distance_m},
                       {"max_distance_m", r.max_distance_m},
                       {"volume_gained_m3", r.volume_gained_m3},
                       {"volume_lost_m3", r.volume_lost_m3},
                       {"points", r.points}});
  }
  const nlohmann::json document = {{"format", "auv-sim-changes 1"},
                                   {"scenario", scenario_name},
                                   {"frame", "world NED, m"},
                                   {"spacing_m", options.spacing_m},
                                   {"min_distance_m", options.min_distance_m},
                                   {"regions", regions}};
  const fs::path json_path = fs::path(dir) / "changes.json";
  const fs::path ply_path = fs::path(dir) / "changes.ply";
  {
    std::ofstream out(ply_path.string() + ".incomplete", std::ios::binary);
    out << "ply\nformat binary_little_endian 1.0\n"
        << "comment true change of the site between two visits (auv sim; world NED, m)\n"
        << "element vertex " << truth.points.size() << "\n"
        << "property float x\nproperty float y\nproperty float z\n"
        << "property float distance\nproperty int region\nend_header\n";
    for (size_t i = 0; i < truth.points.size(); ++i) {
      out.write(reinterpret_cast<const char*>(truth.points[i].data()), 3 * sizeof(float));
      out.write(reinterpret_cast<const char*>(&truth.distances[i]), sizeof(float));
      const int32_t region = truth.region_of_point[i];
      out.write(reinterpret_cast<const char*>(&region), sizeof(region));
    }
    if (!out) throw std::runtime_error(ply_path.string() + ": could not be written");
  }
  {
    std::ofstream out(json_path.string() + ".incomplete");
    out << document.dump(2) << "\n";
    if (!out) throw std::runtime_error(json_path.string() + ": could not be written");
  }
  fs::rename(ply_path.string() + ".incomplete", ply_path);
  fs::rename(json_path.string() + ".incomplete", json_path);
}

bool writeScenarioChangeTruth(const Scenario& scenario, const std::string& dir,
                              const ChangeTruthOptions& options) {
  if (!scenario.later_visit) return false;
  // One read of the mesh file: the later world is the earlier one with the changes applied.
  const Mesh before = loadWorldMeshBeforeChanges(scenario);
  Mesh after = before;
  const std::vector<AppliedChange> applied =
      applySiteChanges(after, scenario.changes, scenario.file);
  writeChangeTruth(measureChangeTruth(before, after, applied, options), dir,
                   fs::path(scenario.file).filename().string(), options);
  Mesh geometry;
  geometry.vertices = after.vertices;
  geometry.triangles = after.triangles;
  geometry.source = scenario.file + " (with its changes)";
  const std::string world = (fs::path(dir) / "world.ply").string();
  saveMesh(geometry, world + ".incomplete.ply");
  fs::rename(world + ".incomplete.ply", world);
  return true;
}

}  // namespace auv::sim
