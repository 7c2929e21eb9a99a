#include "auv/sim/worldgen/world_builders.h"

#include <algorithm>
#include <cmath>

#include "auv/sim/worldgen/atlas_baker.h"

namespace auv::sim::worldgen {

using Eigen::Vector2f;
using Eigen::Vector3d;
using Eigen::Vector3f;

DetailScale::DetailScale(double detail) {
  const float f = static_cast<float>(1.0 / std::sqrt(detail));
  rock_spacing = 0.25f * f;
  seabed_spacing = 0.8f * f;
  block_spacing = 2.0f;
  structure_texel = 0.02f * f;
  seabed_texel = 0.10f * f;
}

LayoutRandom::LayoutRandom(uint64_t seed, const std::string& world) {
  // Mix the world's name in, so two worlds with the same seed do not share their layout draws.
  uint64_t h = 1469598103934665603ull;
  for (char c : world) h = (h ^ static_cast<unsigned char>(c)) * 1099511628211ull;
  std::seed_seq sequence{static_cast<uint32_t>(seed), static_cast<uint32_t>(seed >> 32),
                         static_cast<uint32_t>(h), static_cast<uint32_t>(h >> 32)};
  engine_.seed(sequence);
}

// Drawn from the raw 64-bit stream (not std::uniform_real_distribution, whose algorithm is
// left to the standard library) so a seed gives the same world with any compiler.
float LayoutRandom::uniform(float lo, float hi) {
  const double unit = static_cast<double>(engine_() >> 11) * (1.0 / 9007199254740992.0);
  return lo + static_cast<float>(unit) * (hi - lo);
}

int LayoutRandom::integer(int lo, int hi) {
  return lo + static_cast<int>(engine_() % static_cast<uint64_t>(hi - lo + 1));
}

uint64_t LayoutRandom::next() { return engine_(); }

std::vector<Vector2f> sampleLine(float x0, float x1, float step,
                                 const std::function<float(float)>& f) {
  const int n = std::max(1, static_cast<int>(std::ceil(std::abs(x1 - x0) / step)));
  std::vector<Vector2f> points;
  for (int i = 0; i <= n; ++i) {
    const float x = x0 + (x1 - x0) * static_cast<float>(i) / n;
    points.emplace_back(x, f(x));
  }
  return points;
}

Vector2f pointAlong(const std::vector<Vector2f>& line, float along) {
  for (size_t i = 1; i < line.size(); ++i) {
    const float span = (line[i] - line[i - 1]).norm();
    if (along <= span || i + 1 == line.size()) {
      const float f = span > 0.0f ? std::clamp(along / span, 0.0f, 1.0f) : 0.0f;
      return line[i - 1] + f * (line[i] - line[i - 1]);
    }
    along -= span;
  }
  return line.front();
}

void addRock(WorldDraft& draft, const RockSpec& spec) {
  draft.grids.push_back(buildRock(spec));
  draft.rocks.push_back(spec);
}

RockSpec boulder(const Vector2f& xy, float base_radius, float height, float seabed_z, uint64_t seed,
                 const DetailScale& scale) {
  RockSpec spec;
  spec.ridge = {xy};
  spec.half_width = [base_radius](float, int) { return base_radius; };
  spec.seabed_z = seabed_z;
  spec.bottom_z = seabed_z - 0.6f;
  spec.top_z = seabed_z + height;
  spec.crest = 0.55f;
  spec.taper = 0.15f;
  spec.roughness = 0.18f * std::min(base_radius, height);
  spec.spacing = std::min(scale.rock_spacing, 0.25f * base_radius);
  spec.texel_size = scale.structure_texel;
  spec.seed = seed;
  return spec;
}

namespace {

float widestBase(const RockSpec& rock) {
  float length = 0.0f, widest = 0.0f;
  for (size_t i = 1; i < rock.ridge.size(); ++i)
    length += (rock.ridge[i] - rock.ridge[i - 1]).norm();
  for (int k = 0; k <= 20; ++k) {
    const float along = length * static_cast<float>(k) / 20.0f;
    widest = std::max({widest, rock.half_width(along, 1), rock.half_width(along, -1)});
  }
  float fraction = rockWidthFraction(rock, rock.bottom_z);
  // A profile may lean out (overhang): its widest row can be anywhere.
  for (int k = 0; rock.width_profile && k <= 32; ++k)
    fraction =
        std::max(fraction,
                 rockWidthFraction(rock, rock.bottom_z + (rock.top_z - rock.bottom_z) * k / 32.0f));
  return widest * fraction + rock.roughness;
}

}  // namespace

void addOutcrops(WorldDraft& draft, LayoutRandom& random, int count,
                 const Eigen::AlignedBox2f& area,
                 const std::vector<std::vector<Vector3d>>& mesh_routes, float route_clearance,
                 float radius_lo, float radius_hi, float top_lo, float top_hi, float seabed_z,
                 const DetailScale& scale) {
  std::vector<std::vector<Vector2f>> lines;
  for (const auto& route : mesh_routes) {
    lines.emplace_back();
    for (const Vector3d& p : route) lines.back().emplace_back(p.x(), p.y());
  }
  std::vector<float> widest;
  for (const RockSpec& rock : draft.rocks) widest.push_back(widestBase(rock));
  int placed = 0;
  for (int attempt = 0; attempt < 60 * count && placed < count; ++attempt) {
    const Vector2f xy(random.uniform(area.min().x(), area.max().x()),
                      random.uniform(area.min().y(), area.max().y()));
    const float radius = random.uniform(radius_lo, radius_hi);
    const float top = random.uniform(top_lo, top_hi);
    const uint64_t seed = random.next();
    bool clear = true;
    for (const auto& line : lines)
      clear = clear && distanceToPolyline(line, xy) > radius + route_clearance;
    for (size_t i = 0; i < draft.rocks.size() && clear; ++i)
      clear = distanceToPolyline(draft.rocks[i].ridge, xy) > widest[i] + 0.5f * radius;
    if (!clear) continue;
    RockSpec outcrop = boulder(xy, radius, top - seabed_z, seabed_z, seed, scale);
    outcrop.crest = 0.35f;
    outcrop.taper = 0.3f;
    outcrop.roughness = 0.2f * radius;
    addRock(draft, outcrop);
    widest.push_back(widestBase(outcrop));
    ++placed;
  }
}

bool underRock(const WorldDraft& draft, const Vector2f& xy) {
  for (const RockSpec& rock : draft.rocks) {
    // Nearest ridge vertex (ridges are densely sampled), its arc length and side.
    float best = std::numeric_limits<float>::infinity(), along = 0.0f, best_along = 0.0f;
    int side = 1;
    for (size_t i = 0; i < rock.ridge.size(); ++i) {
      if (i > 0) along += (rock.ridge[i] - rock.ridge[i - 1]).norm();
      const float d = (rock.ridge[i] - xy).norm();
      if (d < best) {
        best = d;
        best_along = along;
        const Vector2f tangent = rock.ridge.size() > 1
                                     ? Vector2f(rock.ridge[std::min(i + 1, rock.ridge.size() - 1)] -
                                                rock.ridge[i > 0 ? i - 1 : 0])
                                     : Vector2f(1, 0);
        const Vector2f offset = xy - rock.ridge[i];
        side = tangent.x() * offset.y() - tangent.y() * offset.x() >= 0.0f ? 1 : -1;
      }
    }
    const float half_width =
        std::min(rock.half_width(best_along, side), rock.half_width(best_along, -side)) *
        rockWidthFraction(rock, rock.seabed_z + 0.3f);
    if (best < half_width - rock.roughness - 0.4f) return true;
  }
  return false;
}

void addRubble(WorldDraft& draft, LayoutRandom& random, const SeabedSpec& seabed, int count,
               float max_height, float reach, const DetailScale& scale) {
  const size_t structures = draft.rocks.size();
  int placed = 0;
  for (int attempt = 0; attempt < 40 * count && placed < count && structures > 0; ++attempt) {
    // Next to a random point of a random rock's base outline.
    const RockSpec& rock = draft.rocks[random.integer(0, static_cast<int>(structures) - 1)];
    const Vector2f centre = rock.ridge[random.integer(0, static_cast<int>(rock.ridge.size()) - 1)];
    const float angle = random.uniform(0.0f, 6.2831853f);
    const float distance = rock.half_width(0.0f, 1) + random.uniform(-1.0f, reach);
    const Vector2f xy = centre + distance * Vector2f(std::cos(angle), std::sin(angle));
    const float radius = random.uniform(0.5f, 1.5f);
    const float height = random.uniform(0.4f, max_height);
    const uint64_t seed = random.next();
    if (!seabed.area.contains(xy) || underRock(draft, xy)) continue;
    const float ground = seabedHeight(seabed, xy.x(), xy.y());
    draft.grids.push_back(buildRock(boulder(xy, radius, height, ground, seed, scale)));
    ++placed;
  }
}

SeabedSpec seabedSpec(float mean_z, float undulation, LayoutRandom& random,
                      const DetailScale& scale) {
  SeabedSpec seabed;
  seabed.mean_z = mean_z;
  seabed.undulation = undulation;
  seabed.spacing = scale.seabed_spacing;
  seabed.texel_size = scale.seabed_texel;
  seabed.seed = random.next();
  return seabed;
}

SeabedSpec addSeabed(WorldDraft& draft, SeabedSpec seabed, float margin) {
  Eigen::AlignedBox2f area;
  for (const SurfaceGrid& grid : draft.grids) {
    for (const Vector3f& p : grid.points) area.extend(p.head<2>());
  }
  const GeneratedWorld& world = draft.world;
  area.extend(nedToMesh(world.start_position).head<2>().cast<float>());
  for (const MissionQuery& q : world.queries)
    area.extend(nedToMesh(q.goal).head<2>().cast<float>());
  seabed.area = Eigen::AlignedBox2f(area.min() - Vector2f::Constant(margin),
                                    area.max() + Vector2f::Constant(margin));
  seabed.covered = [&draft](const Vector2f& xy) { return underRock(draft, xy); };
  draft.grids.push_back(buildSeabed(seabed));
  return seabed;
}

GeneratedWorld finishWorld(WorldDraft& draft, const WorldGenOptions& options,
                           const DetailScale& scale) {
  AtlasOptions atlas;
  atlas.max_texture_size = options.max_texture_size;
  atlas.max_cell_size = std::min(512, options.max_texture_size);
  atlas.seed = options.seed;
  AtlasReport report;
  GeneratedWorld world = std::move(draft.world);
  world.mesh = bakeTexturedMesh(draft.grids, atlas, &report);
  world.mesh.source = world.name + " (generated, seed " + std::to_string(options.seed) + ")";
  world.seed = options.seed;
  world.detail = options.detail;
  world.stats.triangles = world.mesh.triangles.size();
  world.stats.texture_width = report.texture_width;
  world.stats.texture_height = report.texture_height;
  world.stats.structure_texel = scale.structure_texel * report.texel_scale;
  world.stats.seabed_texel = scale.seabed_texel * report.texel_scale;
  draft.grids.clear();
  return world;
}

MissionPlanning threeDimensionalMission(double seabed_depth) {
  MissionPlanning mission;
  mission.fixed_depth = false;
  mission.min_depth = 2.0;
  mission.max_depth = seabed_depth - 2.0;
  mission.min_altitude = 1.5;
  return mission;
}

MissionQuery meshQuery(const std::string& name, const Vector3d& mesh_point, double tolerance) {
  MissionQuery query;
  query.name = name;
  query.goal = meshToNed(mesh_point);
  query.tolerance = tolerance;
  return query;
}

std::vector<Vector3d> meshRoute(const std::vector<Vector3d>& mesh_points) {
  std::vector<Vector3d> route;
  for (const Vector3d& p : mesh_points) route.push_back(meshToNed(p));
  return route;
}

}  // namespace auv::sim::worldgen
