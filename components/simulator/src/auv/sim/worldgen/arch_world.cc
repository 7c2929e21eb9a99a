// `arch`: a rocky barrier running east-west with a natural arch in its middle: rock above open
// water. Under the arch's span (underside ~4.5 m deep, its top above the surface) a passage
// ~7 m wide stays open down to the 12 m seabed; 10 m beyond the barrier a second wall closes
// the way. At the 3 m start depth the span is as solid as the rock beside it, so a vehicle that
// plans in one plane goes round the whole barrier, one that flies in blindly meets the span,
// and one that surfaces under it hits it; the short way dives under the span and turns along
// the wall beyond.
#include <algorithm>
#include <cmath>

#include "auv/sim/worldgen/noise.h"
#include "auv/sim/worldgen/world_builders.h"

namespace auv::sim::worldgen {

using Eigen::Vector2f;
using Eigen::Vector3d;
using Eigen::Vector3f;

namespace {

constexpr float kPi = 3.14159265358979f;

/// The arch's span: a rough tube of elliptical section along mesh y from -half to +half, its
/// centre line sagging towards both ends (where it is buried in the rock beside the passage).
struct SpanSpec {
  float half = 9.0f;         ///< m, half-length along y
  float centre_z = -2.0f;    ///< m, centre line height at y = 0
  float sag = 1.0f;          ///< m, how much lower the centre line is at the ends
  float half_height = 2.5f;  ///< m, vertical semi-axis
  float half_depth = 2.2f;   ///< m, horizontal (x) semi-axis
  float roughness = 0.35f;   ///< m, largest displacement along the normal
  float spacing = 0.25f;
  float texel_size = 0.02f;
  uint64_t seed = 1;
};

SurfaceGrid buildSpan(const SpanSpec& spec) {
  const GradientNoise noise(spec.seed);
  const int rows = std::max(3, static_cast<int>(std::ceil(2.0f * spec.half / spec.spacing)) + 1);
  const float perimeter =
      2.0f * kPi *
      std::sqrt(0.5f * (spec.half_height * spec.half_height + spec.half_depth * spec.half_depth));
  const int cols = std::max(8, static_cast<int>(std::ceil(perimeter / spec.spacing)));
  // Rows run along +y, columns round the section from the top towards +x: d/dc x d/dr points
  // out (at the top, x x y = z).
  SurfaceGrid grid(rows, cols, true, Material::ROCK, spec.texel_size);
  for (int r = 0; r < rows; ++r) {
    const float y = -spec.half + 2.0f * spec.half * static_cast<float>(r) / (rows - 1);
    const float s = y / spec.half;
    const float cz = spec.centre_z - spec.sag * s * s;
    for (int c = 0; c < cols; ++c) {
      const float theta = 2.0f * kPi * static_cast<float>(c) / cols;
      const Vector3f base(spec.half_depth * std::sin(theta), y,
                          cz + spec.half_height * std::cos(theta));
      const Vector3f normal =
          Vector3f(std::sin(theta) / spec.half_depth, 0.0f, std::cos(theta) / spec.half_height)
              .normalized();
      const float lumps = noise.fbm(base, 4.0f, 3),
                  knobs = noise.fbm(base + Vector3f(5, 9, 2), 0.9f, 2);
      grid.at(r, c) =
          base + normal * (spec.roughness * std::clamp(0.75f * lumps + 0.25f * knobs, -1.0f, 1.0f));
    }
  }
  computeNormals(grid);
  return grid;
}

RockSpec ridgeRock(const std::vector<Vector2f>& ridge, float half_width, float top_z,
                   float seabed_z, uint64_t seed, const DetailScale& scale) {
  RockSpec rock;
  rock.ridge = ridge;
  rock.half_width = [half_width](float, int) { return half_width; };
  rock.seabed_z = seabed_z;
  rock.bottom_z = seabed_z - 0.8f;
  rock.top_z = top_z;
  rock.taper = 0.3f;
  rock.roughness = 0.5f;
  rock.spacing = scale.rock_spacing;
  rock.texel_size = scale.structure_texel;
  rock.seed = seed;
  return rock;
}

}  // namespace

GeneratedWorld buildArch(const WorldGenOptions& options) {
  const DetailScale scale(options.detail);
  LayoutRandom random(options.seed, "arch");
  const GradientNoise layout_noise(random.next());

  constexpr float kSeabedZ = -12.0f;
  constexpr float kStartZ = -3.0f;
  constexpr float kUnderZ = -7.0f;                   // route depth under the span
  constexpr float kHalfWidth = 5.0f;                 // m, barrier rocks' half-width at the seabed
  constexpr float kBarrierLength = 34.0f;            // m, each side of the passage
  const float passage = random.uniform(6.5f, 8.0f);  // m, clear width at kUnderZ
  const float top_barrier = random.uniform(1.0f, 2.0f);

  // Barrier rocks west (+y) and east (-y) of the passage; their rounded ends stand
  // `passage` apart at kUnderZ.
  RockSpec probe = ridgeRock({Vector2f::Zero()}, kHalfWidth, top_barrier, kSeabedZ, 0, scale);
  const float reach = kHalfWidth * rockWidthFraction(probe, kUnderZ) + probe.roughness;
  const float end_y = 0.5f * passage + reach;
  WorldDraft draft;
  for (const float side : {1.0f, -1.0f}) {
    // Straight where it meets the span, wandering further out.
    std::vector<Vector2f> ridge = sampleLine(end_y, end_y + kBarrierLength, 0.5f, [&](float a) {
      return 1.5f * noise1d(layout_noise, a + 50.0f * side, 20.0f, 2) * (a - end_y) /
             kBarrierLength;
    });
    for (Vector2f& p : ridge) p = Vector2f(p.y(), side * p.x());
    addRock(draft, ridgeRock(ridge, kHalfWidth, top_barrier, kSeabedZ, random.next(), scale));
  }
  // The span, buried 1 m into both rock ends.
  SpanSpec span;
  span.half = end_y + 1.0f;
  span.centre_z = random.uniform(-2.2f, -1.8f);
  span.spacing = scale.rock_spacing;
  span.texel_size = scale.structure_texel;
  span.seed = random.next();
  draft.grids.push_back(buildSpan(span));

  // The wall beyond, north of the barrier.
  const float wall_x = random.uniform(19.0f, 21.0f);
  std::vector<Vector2f> wall = sampleLine(-40.0f, 40.0f, 0.5f, [&](float y) {
    return wall_x + 1.0f * noise1d(layout_noise, y + 700.0f, 25.0f, 2);
  });
  for (Vector2f& p : wall) p = Vector2f(p.y(), p.x());
  addRock(draft,
          ridgeRock(wall, kHalfWidth, random.uniform(1.0f, 2.0f), kSeabedZ, random.next(), scale));

  GeneratedWorld& world = draft.world;
  world.name = "arch";
  world.description =
      "A rocky barrier with a natural arch (span from ~4.5 m depth to above the surface) over a "
      "7 m wide passage, a wall 10 m beyond: pass under the span and turn along the wall, then "
      "come back under it (3-D; never surface under the span).";
  world.seabed_depth = -kSeabedZ;
  world.visibility = 5.0;

  const double corridor_x = 0.5 * wall_x;  // between the barrier and the wall
  const Vector3d start(-22.0, 0.0, kStartZ);
  const Vector3d goal1(corridor_x, -14.0, -4.0), goal2(-20.0, 12.0, -3.5);
  const Vector3d before(-9.0, 0.0, kUnderZ), under(0.0, 0.0, kUnderZ);
  const Vector3d beyond(corridor_x, 0.0, kUnderZ);
  world.start_position = meshToNed(start);
  world.start_yaw_deg = 0.0;  // north, towards the arch
  world.queries = {meshQuery("under_the_arch", goal1, 2.0),
                   meshQuery("back_under_the_arch", goal2, 2.0)};
  world.layout.routes = {meshRoute({start, before, under, beyond, goal1}),
                         meshRoute({goal1, beyond, under, before, goal2})};
  world.layout.query_depth = -kStartZ;
  world.layout.arch_under = meshToNed(under);
  world.layout.arch_through = Vector3d(1.0, 0.0, 0.0);  // north, in NED as in the mesh
  world.mission = threeDimensionalMission(world.seabed_depth);

  const SeabedSpec seabed = addSeabed(draft, seabedSpec(kSeabedZ, 0.4f, random, scale), 12.0f);
  addRubble(draft, random, seabed, 14, 1.4f, 5.0f, scale);
  return finishWorld(draft, options, scale);
}

}  // namespace auv::sim::worldgen
