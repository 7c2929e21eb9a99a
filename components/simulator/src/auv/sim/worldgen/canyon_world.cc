// `canyon`: the field site of the paper's section 4 (Sant Feliu de Guixols, Figs. 14-16): two
// rocky formations rising from a ~8.5 m seabed to just above the surface, with a narrow canyon
// between them, navigated at 3 m depth. Queries as in the paper: traverse the canyon; go round
// the outer rock back towards the start; traverse again to close the imaging loop.
#include <algorithm>
#include <cmath>
#include <functional>

#include "auv/sim/worldgen/noise.h"
#include "auv/sim/worldgen/world_builders.h"

namespace auv::sim::worldgen {

using Eigen::Vector2f;
using Eigen::Vector3d;

namespace {

/// The reference routes of the three queries (mesh frame): along the canyon's centre line,
/// round the outer rock's north end (at `outside`'s y), and back through the canyon.
std::vector<std::vector<Vector3d>> referenceRoutes(const Vector3d& start,
                                                   const Vector3d& canyon_end,
                                                   const Vector3d& outside, float half,
                                                   const std::function<float(float)>& centreY) {
  const double z = start.z(), outside_y = outside.y();
  std::vector<Vector3d> through_canyon;
  for (float x = -half - 4.0f; x <= half + 4.0f; x += 1.0f)
    through_canyon.emplace_back(x, centreY(x), z);
  std::vector<Vector3d> route1{start};
  route1.insert(route1.end(), through_canyon.begin(), through_canyon.end());
  route1.push_back(canyon_end);
  const std::vector<Vector3d> route2{canyon_end, Vector3d(half + 13.0f, outside_y, z), outside};
  std::vector<Vector3d> route3{outside, Vector3d(start.x(), outside_y, z), start};
  route3.insert(route3.end(), through_canyon.begin(), through_canyon.end());
  route3.push_back(canyon_end);
  return {route1, route2, route3};
}

}  // namespace

GeneratedWorld buildCanyon(const WorldGenOptions& options) {
  const DetailScale scale(options.detail);
  LayoutRandom random(options.seed, "canyon");
  const GradientNoise layout_noise(random.next());

  constexpr float kSeabedZ = -8.5f;
  constexpr float kQueryZ = -3.0f;         // the paper's 3 m navigation depth
  constexpr float kNominalWidth = 6.0f;    // m, canyon width at query depth before variation
  constexpr float kWidthSwing = 0.8f;      // m, designed +- variation along the canyon
  constexpr float kRoughness = 0.5f;       // m, largest displacement of the canyon's walls
  constexpr float kOuterRoughness = 1.6f;  // m, elsewhere: lumpy, irregular outlines
  const float length = random.uniform(32.0f, 38.0f);  // canyon length = outer rock's ridge
  const float half = 0.5f * length;

  // Canyon centre line and width at query depth, both smooth functions of x (north).
  auto centreY = [&](float x) {
    return std::clamp(1.6f * noise1d(layout_noise, x + 100.0f, 45.0f, 2), -1.2f, 1.2f);
  };
  auto widthAt = [&](float x) {
    return kNominalWidth +
           kWidthSwing *
               std::clamp(1.4f * noise1d(layout_noise, x - 300.0f, 14.0f, 2), -1.0f, 1.0f);
  };

  // Rock B, the outer rock (east, mesh -y), as long as the canyon; rock A, the inner one (west),
  // longer at both ends. The walls facing the canyon are placed exactly at query depth, however
  // the crest lines wander; the outer walls vary freely.
  auto rockBase = [&](float top_z) {
    RockSpec rock;
    rock.seabed_z = kSeabedZ;
    rock.bottom_z = kSeabedZ - 0.7f;
    rock.top_z = top_z;
    rock.taper = 0.3f;
    rock.roughness = kOuterRoughness;
    rock.roughness_at = [&](const Vector2f& xy) {
      // Distance outside the band holding both facing walls, along the whole inner rock.
      const float across = std::abs(xy.y() - centreY(xy.x())) - (0.5f * kNominalWidth + 2.5f);
      const float along = std::max(-half - 16.0f - xy.x(), xy.x() - half - 14.0f);
      const float outside = std::max(across, along);
      return kRoughness + (kOuterRoughness - kRoughness) * smoothStep(0.0f, 4.0f, outside);
    };
    rock.spacing = scale.rock_spacing;
    rock.texel_size = scale.structure_texel;
    rock.seed = random.next();
    return rock;
  };
  // `facing` = +1 if the rock lies west of the canyon (mesh +y). Its facing wall at query depth
  // is at centreY -+ width/2; the crest line wanders 2.5-5.5 m behind it.
  auto canyonRock = [&](float x0, float x1, float top_z, int facing, float outer_mean,
                        float outer_swing) {
    RockSpec rock = rockBase(top_z);
    const GradientNoise wander(random.next()), outer(random.next());
    auto wallY = [&, facing](float x) { return centreY(x) + facing * 0.5f * widthAt(x); };
    rock.ridge = sampleLine(x0, x1, 0.5f, [&, facing, wander](float x) {
      return wallY(x) +
             facing * (4.0f + 1.5f * std::clamp(1.3f * noise1d(wander, x, 16.0f, 2), -1.0f, 1.0f));
    });
    const float fraction = rockWidthFraction(rock, kQueryZ);
    // The ridge runs north (+x): its left side (+1) is west. Facing side = -facing.
    rock.half_width = [&, wallY, ridge = rock.ridge, fraction, facing, outer, outer_mean,
                       outer_swing](float along, int side) {
      const Vector2f p = pointAlong(ridge, along);
      const float at_query =
          side == -facing
              ? std::abs(p.y() - wallY(p.x()))
              : outer_mean +
                    outer_swing * std::clamp(2.0f * noise1d(outer, p.x(), 9.0f, 3), -1.0f, 1.0f);
      return at_query / fraction;
    };
    return rock;
  };
  // A spur: a lower, narrower rock branching off a rock's outer side.
  auto spur = [&](const RockSpec& parent, float along_fraction, int side, float length_m) {
    RockSpec rock = rockBase(parent.top_z - random.uniform(1.0f, 2.5f));
    float total = 0.0f;
    for (size_t i = 1; i < parent.ridge.size(); ++i)
      total += (parent.ridge[i] - parent.ridge[i - 1]).norm();
    const Vector2f root = pointAlong(parent.ridge, along_fraction * total);
    const float angle = random.uniform(-0.6f, 0.6f);
    const Vector2f direction = Eigen::Rotation2Df(angle) * Vector2f(0.0f, static_cast<float>(side));
    const float width = random.uniform(2.2f, 3.2f) / rockWidthFraction(rock, kQueryZ);
    for (float t = 0.0f; t <= length_m; t += 0.5f) rock.ridge.push_back(root + t * direction);
    const GradientNoise bumps(random.next());
    rock.half_width = [width, length_m, bumps](float along, int s) {
      const float tip = 1.0f - 0.35f * along / length_m;  // narrower towards the tip
      return width * tip * (1.0f + 0.25f * noise1d(bumps, along + 40.0f * s, 5.0f, 2));
    };
    return rock;
  };

  const float top_a = random.uniform(1.4f, 2.2f), top_b = random.uniform(0.6f, 1.2f);
  const RockSpec rock_a = canyonRock(-half - 6.0f, half + 4.0f, top_a, +1, 5.5f, 2.5f);
  const RockSpec rock_b = canyonRock(-half, half, top_b, -1, 5.0f, 2.0f);

  WorldDraft draft;
  GeneratedWorld& world = draft.world;
  world.name = "canyon";
  world.description =
      "Two rocky formations forming a narrow canyon (paper section 4, Sant Feliu de Guixols), "
      "navigated at 3 m depth: traverse the canyon, go round the outer rock back towards the "
      "start, traverse again to close the loop.";
  world.seabed_depth = -kSeabedZ;
  world.visibility = 4.5;  // the paper: ~4.5 m inside the canyon, ~3 m outside

  const float spur_at = random.uniform(0.25f, 0.75f), spur_length = random.uniform(8.0f, 11.0f);
  addRock(draft, rock_a);
  addRock(draft, spur(rock_a, spur_at, +1, spur_length));
  addRock(draft, rock_b);
  // How far east the outer rock reaches near query depth, from the built walls.
  float east_of_b = 0.0f;
  for (size_t g = 2; g < draft.grids.size(); ++g) {
    for (const Eigen::Vector3f& p : draft.grids[g].points)
      if (p.z() > kQueryZ - 1.5f) east_of_b = std::min(east_of_b, p.y());
  }

  // Queries (mesh frame). The start and the canyon's far end sit 1 m east of the centre line,
  // away from the inner rock, which reaches past the canyon at both ends.
  const double z = kQueryZ;
  const Vector3d start(-half - 13.0f, centreY(-half - 13.0f) - 1.0f, z);
  const Vector3d canyon_end(half + 11.0f, centreY(half + 11.0f) - 1.0f, z);
  const double outside_y = east_of_b - 6.0f;
  const Vector3d outside(-half - 2.0f, outside_y, z);
  world.start_position = meshToNed(start);
  world.start_yaw_deg = 0.0;
  world.queries = {meshQuery("traverse", canyon_end, 2.0),
                   meshQuery("circumnavigate_outer_rock", outside, 2.0),
                   meshQuery("traverse_again", canyon_end, 2.0)};

  const std::vector<std::vector<Vector3d>> routes =
      referenceRoutes(start, canyon_end, outside, half, centreY);
  const std::vector<Vector3d>&route1 = routes[0], &route2 = routes[1], &route3 = routes[2];
  world.layout.routes = {meshRoute(route1), meshRoute(route2), meshRoute(route3)};
  for (float x = -half + 1.0f; x <= half - 1.0f; x += 1.0f)
    world.layout.canyon_axis.push_back(meshToNed(Vector3d(x, centreY(x), z)));
  world.layout.canyon_min_width = kNominalWidth - kWidthSwing - 2.0f * kRoughness;
  world.layout.canyon_max_width = kNominalWidth + kWidthSwing + 2.0f * kRoughness;
  world.layout.query_depth = -kQueryZ;

  // Outlying rocks off the outer walls, clear of the routes.
  const Eigen::AlignedBox2f outcrop_area(Vector2f(start.x() - 6.0f, outside_y - 10.0f),
                                         Vector2f(canyon_end.x() + 8.0f, east_of_b + 45.0f));
  addOutcrops(draft, random, 2, outcrop_area, {route1, route2, route3}, 5.0f, 1.5f, 2.5f, -2.5f,
              0.5f, kSeabedZ, scale);

  const SeabedSpec seabed = addSeabed(draft, seabedSpec(kSeabedZ, 0.35f, random, scale), 15.0f);
  // Fallen blocks at the foot of the rocks, well below the navigation depth.
  addRubble(draft, random, seabed, 16, 1.6f, 6.0f, scale);
  return finishWorld(draft, options, scale);
}

}  // namespace auv::sim::worldgen
