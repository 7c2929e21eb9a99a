// `dead_end_bay`: a harder world for the planner. A U-shaped rock wall opens towards the start
// and the goal lies behind its closed end, so the straight route leads into a dead end that a
// 20 m sonar only reveals once the vehicle is inside. The way round is through one of two
// passages between the bay's arms and flanking rocks (about 7 m and 9 m wide at 3 m depth),
// past tall boulders that reach above the navigation depth.
#include <algorithm>
#include <cmath>

#include "auv/sim/worldgen/noise.h"
#include "auv/sim/worldgen/world_builders.h"

namespace auv::sim::worldgen {

using Eigen::Vector2f;
using Eigen::Vector3d;

GeneratedWorld buildDeadEndBay(const WorldGenOptions& options) {
  const DetailScale scale(options.detail);
  LayoutRandom random(options.seed, "dead_end_bay");
  const GradientNoise layout_noise(random.next());

  constexpr float kSeabedZ = -9.0f;
  constexpr float kQueryZ = -3.0f;
  constexpr float kRoughness = 0.5f;       // m, largest displacement of the passages' walls
  constexpr float kOuterRoughness = 1.4f;  // m, elsewhere
  constexpr float kPi = 3.14159265f;
  const float bay_radius = random.uniform(9.5f, 11.0f);   // m, ridge radius of the closed end
  const float arm_length = random.uniform(22.0f, 26.0f);  // m, straight arms towards the start
  const float arm_outer = 3.8f, arm_swing = 0.4f;         // m, arms' outer half-width at 3 m

  // The U's crest line: up the east arm (mesh -y), round the closed end in the north, down the
  // west arm. Its left side faces into the bay.
  std::vector<Vector2f> u_ridge;
  for (float x = -arm_length; x < 0.0f; x += 0.5f) u_ridge.emplace_back(x, -bay_radius);
  const int arc_steps = static_cast<int>(std::ceil(kPi * bay_radius / 0.5f));
  for (int k = 0; k <= arc_steps; ++k) {
    const float angle = -0.5f * kPi + kPi * static_cast<float>(k) / arc_steps;
    u_ridge.emplace_back(bay_radius * std::cos(angle), bay_radius * std::sin(angle));
  }
  for (float x = -0.5f; x >= -arm_length; x -= 0.5f) u_ridge.emplace_back(x, bay_radius);

  // Passages beside the arms, between them and flanking rocks: the way round the bay.
  struct Passage {
    float side;      // +1 west (mesh +y), -1 east
    float width;     // m, nominal at query depth
    float centre_y;  // m, mesh y of the passage's centre line
  };
  std::vector<Passage> passages = {{+1.0f, 7.0f, 0.0f}, {-1.0f, 9.0f, 0.0f}};
  for (Passage& passage : passages) {
    const float arm_wall = bay_radius + arm_outer + arm_swing + kRoughness;  // |y| it can reach
    passage.centre_y = passage.side * (arm_wall + 0.5f * passage.width - arm_swing - kRoughness);
  }
  // Walls along the passages keep to their design; elsewhere the rock is lumpier.
  auto roughnessAt = [passages, arm_length, bay_radius](const Vector2f& xy) {
    float outside = 1e9f;
    for (const Passage& p : passages) {
      const float across = std::abs(xy.y() - p.centre_y) - (0.5f * p.width + 2.0f);
      const float along = std::max(-arm_length - 8.0f - xy.x(), xy.x() - bay_radius - 3.0f);
      outside = std::min(outside, std::max(across, along));
    }
    return kRoughness + (kOuterRoughness - kRoughness) * smoothStep(0.0f, 4.0f, outside);
  };

  RockSpec bay;
  bay.ridge = u_ridge;
  bay.seabed_z = kSeabedZ;
  bay.bottom_z = kSeabedZ - 1.1f;
  bay.top_z = random.uniform(0.8f, 1.5f);
  bay.taper = 0.3f;
  bay.roughness = kOuterRoughness;
  bay.roughness_at = roughnessAt;
  bay.spacing = scale.rock_spacing;
  bay.texel_size = scale.structure_texel;
  bay.seed = random.next();
  const float bay_fraction = rockWidthFraction(bay, kQueryZ);
  bay.half_width = [&layout_noise, bay_fraction, arm_outer, arm_swing](float along, int side) {
    const float n = std::clamp(
        1.4f * noise1d(layout_noise, along + (side > 0 ? 0.0f : 500.0f), 10.0f, 2), -1.0f, 1.0f);
    const float at_query = side > 0 ? 3.0f + 0.8f * n : arm_outer + arm_swing * n;
    return at_query / bay_fraction;
  };

  WorldDraft draft;
  for (const Passage& passage : passages) {
    const float facing = 4.0f;  // m, flank's half-width at query depth towards the passage
    const float ridge_y = passage.centre_y + passage.side * (0.5f * passage.width + facing);
    RockSpec flank = bay;
    const float x0 = -arm_length - random.uniform(1.0f, 3.0f), x1 = random.uniform(-4.0f, 0.0f);
    flank.ridge = sampleLine(x0, x1, 0.5f, [&](float x) {
      return ridge_y +
             passage.side * 1.2f * noise1d(layout_noise, x + 900.0f * passage.side, 30.0f, 1);
    });
    flank.top_z = random.uniform(0.0f, 1.0f);
    flank.seed = random.next();
    const float fraction = rockWidthFraction(flank, kQueryZ);
    const float side_facing = passage.side > 0 ? -1.0f : 1.0f;  // ridge runs north (+x)
    const std::vector<Vector2f> ridge = flank.ridge;
    const float centre_y = passage.centre_y, width = passage.width, towards = passage.side;
    flank.half_width = [&layout_noise, ridge, fraction, side_facing, centre_y, width, towards,
                        facing](float along, int side) {
      const Vector2f p = pointAlong(ridge, along);
      if (static_cast<float>(side) == side_facing) {
        // Keep the passage's wall where designed, however the ridge wanders.
        const float swing =
            0.8f *
            std::clamp(1.4f * noise1d(layout_noise, p.x() - 40.0f * towards, 9.0f, 2), -1.0f, 1.0f);
        return (std::abs(p.y() - centre_y) - 0.5f * width + swing) / fraction;
      }
      (void)facing;
      return (4.5f +
              1.5f * std::clamp(1.3f * noise1d(layout_noise, p.x() + 77.0f * towards, 9.0f, 3),
                                -1.0f, 1.0f)) /
             fraction;
    };
    addRock(draft, flank);
  }
  addRock(draft, bay);

  GeneratedWorld& world = draft.world;
  world.name = "dead_end_bay";
  world.description =
      "A U-shaped rocky bay opening towards the start with the goal behind its closed end: the "
      "direct route is a dead end; the way round is through narrow passages beside the arms.";
  world.seabed_depth = -kSeabedZ;
  world.visibility = 4.0;

  const double z = kQueryZ;
  const Vector3d start(-arm_length - 16.0f, 0.0, z);
  const Vector3d goal(bay_radius + arm_outer + 15.0f, 0.0, z);
  world.start_position = meshToNed(start);
  world.start_yaw_deg = 0.0;
  world.queries = {meshQuery("reach_behind_bay", goal, 2.0),
                   meshQuery("return_to_start", start, 2.0)};
  const float west_y = passages[0].centre_y;
  const std::vector<Vector3d> route{start, Vector3d(start.x(), west_y, z),
                                    Vector3d(bay_radius + 8.0f, west_y, z), goal};
  world.layout.routes = {meshRoute(route), meshRoute({route.rbegin(), route.rend()})};
  world.layout.query_depth = -kQueryZ;
  const float east_y = passages[1].centre_y;
  const std::vector<Vector3d> east_route{start, Vector3d(start.x(), east_y, z),
                                         Vector3d(bay_radius + 8.0f, east_y, z), goal};

  // Tall outcrops reaching above the navigation depth, kept off both routes and the queries.
  const Eigen::AlignedBox2f outcrop_area(Vector2f(start.x() - 12.0f, -38.0f),
                                         Vector2f(goal.x() + 10.0f, 38.0f));
  addOutcrops(draft, random, 6, outcrop_area, {route, east_route}, 4.0f, 1.8f, 2.8f, -1.8f, 0.3f,
              kSeabedZ, scale);

  const SeabedSpec seabed = addSeabed(draft, seabedSpec(kSeabedZ, 0.4f, random, scale), 12.0f);
  addRubble(draft, random, seabed, 14, 1.6f, 5.0f, scale);
  return finishWorld(draft, options, scale);
}

}  // namespace auv::sim::worldgen
