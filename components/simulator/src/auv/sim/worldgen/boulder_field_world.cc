// `boulder_field`: rounded boulders on a 10 m seabed, natural terrain that is not a vertical
// extrusion at the navigation depth. Many tops lie just below the 4 m start depth, so a vehicle
// held at 4 m passes over them with less than 1.5 m of altitude and a horizontal profiling sonar
// never sees them; a few tall ones reach above 2 m depth and must be gone around (one stands on
// the direct line of the first query); low ones fill the seabed. The queries cross the field:
// the planner decides in 3-D whether to rise over a top or go round it.
#include <algorithm>
#include <cmath>

#include "auv/sim/worldgen/world_builders.h"

namespace auv::sim::worldgen {

using Eigen::Vector2f;
using Eigen::Vector3d;

namespace {

struct Placed {
  Vector2f xy;
  float radius;
};

bool overlaps(const std::vector<Placed>& placed, const Vector2f& xy, float radius, float gap) {
  for (const Placed& p : placed)
    if ((p.xy - xy).norm() < p.radius + radius + gap) return true;
  return false;
}

std::vector<Vector2f> flat(const std::vector<Vector3d>& route) {
  std::vector<Vector2f> line;
  for (const Vector3d& p : route) line.emplace_back(p.x(), p.y());
  return line;
}

}  // namespace

GeneratedWorld buildBoulderField(const WorldGenOptions& options) {
  const DetailScale scale(options.detail);
  LayoutRandom random(options.seed, "boulder_field");

  constexpr float kSeabedZ = -10.0f;
  constexpr float kStartZ = -4.0f;            // start and goal depth
  constexpr float kCrossZ = -2.4f;            // over the shallow tops, inside the band's 2 m limit
  constexpr float kShallowRoughness = 0.25f;  // m: shallow tops stay within 0.25 m of design
  constexpr float kEnd = 30.0f;               // m, start and goals this far from the centre

  // The blocker: a tall boulder on the first query's direct line, and the way round it.
  const float blocker_x = random.uniform(-3.0f, 3.0f);
  const float blocker_r = random.uniform(2.4f, 3.0f);
  const float side = random.integer(0, 1) ? 1.0f : -1.0f;
  const float detour_y = side * (blocker_r + 4.0f);
  const double z = kCrossZ;
  const Vector3d start(-kEnd, 0.0, kStartZ), goal1(kEnd, 0.0, kStartZ);
  const Vector3d goal2(-kEnd, 14.0, kStartZ);
  const std::vector<Vector3d> route1{start,
                                     Vector3d(-kEnd + 6.0, 0.0, z),
                                     Vector3d(blocker_x - blocker_r - 6.0, 0.0, z),
                                     Vector3d(blocker_x - blocker_r - 1.0, detour_y, z),
                                     Vector3d(blocker_x + blocker_r + 1.0, detour_y, z),
                                     Vector3d(blocker_x + blocker_r + 6.0, 0.0, z),
                                     Vector3d(kEnd - 6.0, 0.0, z),
                                     goal1};
  const std::vector<Vector3d> route2{goal1, Vector3d(kEnd - 6.0, 0.0, z),
                                     Vector3d(-kEnd + 6.0, goal2.y(), z), goal2};
  const std::vector<std::vector<Vector2f>> lines{flat(route1), flat(route2)};

  WorldDraft draft;
  std::vector<Placed> placed;
  auto place = [&](const Vector2f& xy, float radius, float top_z, float roughness) {
    RockSpec rock = boulder(xy, radius, top_z - kSeabedZ, kSeabedZ, random.next(), scale);
    if (roughness > 0.0f) rock.roughness = roughness;
    addRock(draft, rock);
    placed.push_back({xy, radius});
  };
  GeneratedWorld& world = draft.world;

  // Tall boulders: the blocker, then a few more off both routes.
  const float blocker_top = random.uniform(-1.5f, 0.5f);
  place(Vector2f(blocker_x, 0.0f), blocker_r, blocker_top, 0.0f);
  world.layout.tall_boulder_tops.push_back(meshToNed(Vector3d(blocker_x, 0.0, blocker_top)));
  for (int attempt = 0, tall = 0; attempt < 200 && tall < 3; ++attempt) {
    const Vector2f xy(random.uniform(-20.0f, 20.0f), random.uniform(-16.0f, 24.0f));
    const float radius = random.uniform(2.0f, 2.8f), top = random.uniform(-1.8f, 0.3f);
    bool clear = !overlaps(placed, xy, radius, 2.0f);
    for (const auto& line : lines) clear = clear && distanceToPolyline(line, xy) > radius + 3.5f;
    if (!clear) continue;
    place(xy, radius, top, 0.0f);
    world.layout.tall_boulder_tops.push_back(meshToNed(Vector3d(xy.x(), xy.y(), top)));
    ++tall;
  }
  // Shallow boulders on (or next to) the queries' direct lines, tops 0.3-1.2 m below 4 m.
  for (int attempt = 0, shallow = 0; attempt < 400 && shallow < 10; ++attempt) {
    const float t = random.uniform(0.0f, 1.0f);
    const bool first = random.integer(0, 1) == 0;
    const Vector2f a = first ? Vector2f(-kEnd, 0.0f) : Vector2f(kEnd, 0.0f);
    const Vector2f b = first ? Vector2f(kEnd, 0.0f) : Vector2f(-kEnd, goal2.y());
    const Vector2f xy = a + t * (b - a) + Vector2f(0.0f, random.uniform(-2.0f, 2.0f));
    const float radius = random.uniform(2.2f, 3.2f), top = random.uniform(-5.2f, -4.3f);
    if (std::abs(xy.x()) > 18.0f || overlaps(placed, xy, radius, 0.6f)) continue;
    place(xy, radius, top, kShallowRoughness);
    world.layout.shallow_boulder_tops.push_back(meshToNed(Vector3d(xy.x(), xy.y(), top)));
    ++shallow;
  }
  // Low boulders anywhere, well below the start depth.
  for (int attempt = 0, low = 0; attempt < 400 && low < 14; ++attempt) {
    const Vector2f xy(random.uniform(-26.0f, 26.0f), random.uniform(-16.0f, 22.0f));
    const float radius = random.uniform(1.0f, 2.0f), top = random.uniform(-8.5f, -6.5f);
    if (overlaps(placed, xy, radius, 0.8f)) continue;
    if ((xy - Vector2f(start.x(), start.y())).norm() < 4.0f + radius ||
        (xy - Vector2f(goal1.x(), goal1.y())).norm() < 4.0f + radius ||
        (xy - Vector2f(goal2.x(), goal2.y())).norm() < 4.0f + radius)
      continue;
    place(xy, radius, top, 0.0f);
    ++low;
  }

  world.name = "boulder_field";
  world.description =
      "Rounded boulders on a 10 m seabed: many tops just below the 4 m start depth, a few tall "
      "ones reaching above 2 m, low ones between; cross the field twice, over or around (3-D).";
  world.seabed_depth = -kSeabedZ;
  world.visibility = 5.0;
  world.start_position = meshToNed(start);
  world.start_yaw_deg = 0.0;  // north, towards the first goal
  world.queries = {meshQuery("cross_field", goal1, 2.0),
                   meshQuery("cross_back_diagonally", goal2, 2.0)};
  world.layout.routes = {meshRoute(route1), meshRoute(route2)};
  world.layout.query_depth = -kStartZ;
  world.mission = threeDimensionalMission(world.seabed_depth);

  addSeabed(draft, seabedSpec(kSeabedZ, 0.3f, random, scale), 12.0f);
  return finishWorld(draft, options, scale);
}

}  // namespace auv::sim::worldgen
