#pragma once
// Internal to the world generator: the builders of the shipped worlds and what they share.

#include <Eigen/Core>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "auv/sim/worldgen/shapes.h"
#include "auv/sim/worldgen/world_generator.h"

namespace auv::sim::worldgen {

/// Grid spacings and texel sizes for a detail level: counts of triangles and of texels both
/// grow in proportion to `detail`.
struct DetailScale {
  explicit DetailScale(double detail);
  float rock_spacing;     ///< m, rock grid spacing
  float seabed_spacing;   ///< m
  float block_spacing;    ///< m, flat faces (geometry needs none; keeps cells small)
  float structure_texel;  ///< m, rock and concrete
  float seabed_texel;     ///< m
};

/// Seeded random numbers for a world's layout (one stream per world and seed).
class LayoutRandom {
 public:
  LayoutRandom(uint64_t seed, const std::string& world);
  float uniform(float lo, float hi);
  int integer(int lo, int hi);  ///< inclusive
  uint64_t next();              ///< a fresh seed for a shape's noise

 private:
  std::mt19937_64 engine_;
};

/// The world under construction: shapes plus what the scenario needs.
struct WorldDraft {
  GeneratedWorld world;
  std::vector<SurfaceGrid> grids;
  std::vector<RockSpec> rocks;  ///< rocks added so far (for seabed holes and spacing checks)
};

GeneratedWorld buildBreakwater(const WorldGenOptions& options);
GeneratedWorld buildCanyon(const WorldGenOptions& options);
GeneratedWorld buildDeadEndBay(const WorldGenOptions& options);
GeneratedWorld buildBoulderField(const WorldGenOptions& options);
GeneratedWorld buildArch(const WorldGenOptions& options);
GeneratedWorld buildLeaningReef(const WorldGenOptions& options);

/// The mission mode of the natural-terrain worlds: 3-D planning in a band from 2 m depth to
/// 2 m above the seabed, 1.5 m minimum altitude.
MissionPlanning threeDimensionalMission(double seabed_depth);

/// Points (x, f(x)) for x from x0 to x1 every `step` (mesh xy).
std::vector<Eigen::Vector2f> sampleLine(float x0, float x1, float step,
                                        const std::function<float(float)>& f);
/// The point at arc length `along` of a polyline.
Eigen::Vector2f pointAlong(const std::vector<Eigen::Vector2f>& line, float along);

/// Adds a rock (and remembers it).
void addRock(WorldDraft& draft, const RockSpec& spec);
/// Adds `count` low boulders (tops at most `max_height` m above the seabed) on the seabed
/// within `reach` m of the existing rocks' bases, away from the queries' depth.
void addRubble(WorldDraft& draft, LayoutRandom& random, const SeabedSpec& seabed, int count,
               float max_height, float reach, const DetailScale& scale);
/// Adds up to `count` round outcrops (base radius in [radius_lo, radius_hi] m, top height in
/// [top_lo, top_hi] m, mesh z) inside `area`, at least `route_clearance` m (plus their radius)
/// from every route (mesh points) and clear of the rocks already there.
void addOutcrops(WorldDraft& draft, LayoutRandom& random, int count,
                 const Eigen::AlignedBox2f& area,
                 const std::vector<std::vector<Eigen::Vector3d>>& mesh_routes,
                 float route_clearance, float radius_lo, float radius_hi, float top_lo,
                 float top_hi, float seabed_z, const DetailScale& scale);
/// True if mesh point `xy` lies under a remembered rock (well inside its base).
bool underRock(const WorldDraft& draft, const Eigen::Vector2f& xy);
/// A round boulder at `xy` standing on the seabed.
RockSpec boulder(const Eigen::Vector2f& xy, float base_radius, float height, float seabed_z,
                 uint64_t seed, const DetailScale& scale);

/// A seabed at mean height `mean_z` (mesh z) with relief of `undulation` m, at the scale's
/// detail, seeded from `random` (its area is left to addSeabed()).
SeabedSpec seabedSpec(float mean_z, float undulation, LayoutRandom& random,
                      const DetailScale& scale);
/// Seabed under everything built so far plus `margin` m, holes under the rocks; adds it and
/// returns its spec with the area filled in.
SeabedSpec addSeabed(WorldDraft& draft, SeabedSpec seabed, float margin);

/// Bakes the grids into the world's mesh and fills its stats.
GeneratedWorld finishWorld(WorldDraft& draft, const WorldGenOptions& options,
                           const DetailScale& scale);

/// A query at mesh point (x, y, z) named `name`.
MissionQuery meshQuery(const std::string& name, const Eigen::Vector3d& mesh_point,
                       double tolerance);
/// A route from mesh points, in NED.
std::vector<Eigen::Vector3d> meshRoute(const std::vector<Eigen::Vector3d>& mesh_points);

}  // namespace auv::sim::worldgen
