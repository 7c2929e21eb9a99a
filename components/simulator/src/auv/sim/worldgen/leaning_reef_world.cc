// `leaning_reef`: a long reef running north-south whose face leans out below the navigation
// depth. Near the surface the face is steep (about 4 m from the crest line at 3 m depth); below
// 3 m it leans out to a lip about 8 m out at 6-7 m depth, then is undercut back towards the
// seabed (rock over open water under the lip). A horizontal profiling sonar at 3 m sees the
// face where it is furthest away; the rock that comes closest is below it. The queries go
// deep along the lip, then back up over it.
#include <algorithm>
#include <cmath>

#include "auv/sim/worldgen/noise.h"
#include "auv/sim/worldgen/world_builders.h"

namespace auv::sim::worldgen {

using Eigen::Vector2f;
using Eigen::Vector3d;

namespace {

/// Distance (m) of the face from the crest line at height z (mesh z, up).
struct ReefProfile {
  float top_z = 0.8f;     ///< crest, above the surface
  float steep_z = -0.5f;  ///< the crest rounds over into the steep face here
  float lean_z = -3.0f;   ///< the face starts leaning out here (the navigation depth)
  float lip_z = -6.5f;    ///< furthest out
  float under_z = -8.5f;  ///< bottom of the undercut
  float crest_out = 3.6f, lean_out = 4.2f, lip_out = 8.0f, under_out = 6.0f, foot_out = 6.5f;
  float bottom_z = -12.0f;

  float operator()(float z) const {
    if (z >= top_z) return 0.0f;
    if (z >= steep_z) {
      const float t = (z - steep_z) / (top_z - steep_z);
      return crest_out * std::sqrt(std::max(0.0f, 1.0f - t * t));
    }
    if (z >= lean_z) return crest_out + (lean_out - crest_out) * (steep_z - z) / (steep_z - lean_z);
    if (z >= lip_z) return lean_out + (lip_out - lean_out) * smoothStep(lean_z, lip_z, z);
    if (z >= under_z) return lip_out + (under_out - lip_out) * smoothStep(lip_z, under_z, z);
    return under_out + (foot_out - under_out) * smoothStep(under_z, bottom_z, z);
  }
};

}  // namespace

GeneratedWorld buildLeaningReef(const WorldGenOptions& options) {
  const DetailScale scale(options.detail);
  LayoutRandom random(options.seed, "leaning_reef");
  const GradientNoise layout_noise(random.next());

  constexpr float kSeabedZ = -11.0f;
  constexpr float kHalfLength = 45.0f;  // m, the reef's crest line runs x in +-45
  constexpr float kWander = 1.0f;       // m, the crest line's largest sideways swing
  constexpr float kRoughness = 0.4f;

  ReefProfile profile;
  profile.top_z = random.uniform(0.5f, 1.2f);
  profile.lip_z = random.uniform(-7.0f, -6.0f);
  profile.under_z = profile.lip_z - 2.0f;
  profile.lip_out = random.uniform(7.5f, 8.5f);
  profile.bottom_z = kSeabedZ - 1.0f;
  const float reference = profile.lip_out;  // half_width; the profile is a fraction of it

  RockSpec reef;
  reef.ridge = sampleLine(-kHalfLength, kHalfLength, 0.5f, [&](float x) {
    return kWander * std::clamp(1.4f * noise1d(layout_noise, x, 30.0f, 2), -1.0f, 1.0f);
  });
  reef.half_width = [reference](float, int) { return reference; };
  reef.seabed_z = kSeabedZ;
  reef.bottom_z = profile.bottom_z;
  reef.top_z = profile.top_z;
  reef.width_profile = [profile, reference](float z) { return profile(z) / reference; };
  reef.roughness = kRoughness;
  reef.spacing = scale.rock_spacing;
  reef.texel_size = scale.structure_texel;
  reef.seed = random.next();

  WorldDraft draft;
  addRock(draft, reef);

  GeneratedWorld& world = draft.world;
  world.name = "leaning_reef";
  world.description =
      "A reef whose face leans out below 3 m depth to an undercut lip ~8 m out at 6-7 m: the "
      "rock nearest the vehicle is below the navigation depth. Go deep along the lip, then back "
      "up over it (3-D).";
  world.seabed_depth = -kSeabedZ;
  world.visibility = 5.0;

  // The vehicle works the east face (mesh -y). Its furthest reach: lip + wander + roughness.
  const double face = profile.lip_out + kWander + kRoughness;
  const Vector3d start(-32.0, -face - 3.5, -3.0);
  const Vector3d goal1(25.0, -face - 2.6, profile.lip_z - 0.8);
  const Vector3d goal2(-22.0, -(profile.lean_out + kWander + kRoughness) - 2.6, -2.5);
  world.start_position = meshToNed(start);
  world.start_yaw_deg = 0.0;  // north, along the reef
  world.queries = {meshQuery("along_the_lip_deep", goal1, 2.0),
                   meshQuery("up_over_the_lip", goal2, 2.0)};
  const Vector3d rise(20.0, -face - 3.5, -3.0);
  world.layout.routes = {meshRoute({start, goal1}), meshRoute({goal1, rise, goal2})};
  world.layout.query_depth = -start.z();
  for (float x = -25.0f; x <= 25.0f; x += 10.0f)
    world.layout.reef_stations.push_back(meshToNed(Vector3d(x, -face - 8.0, 0.0)));
  world.layout.reef_towards = meshToNed(Vector3d(0.0, 1.0, 0.0));  // west, towards the reef
  world.mission = threeDimensionalMission(world.seabed_depth);

  const SeabedSpec seabed = addSeabed(draft, seabedSpec(kSeabedZ, 0.35f, random, scale), 12.0f);
  addRubble(draft, random, seabed, 16, 0.6f, 5.0f, scale);  // low: the deep goal is near
  return finishWorld(draft, options, scale);
}

}  // namespace auv::sim::worldgen
