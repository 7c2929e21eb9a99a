#pragma once
// The shapes the worlds are made of, as surface grids in the mesh frame (x north, y west,
// z up, z = 0 the sea surface): rocky formations around a crest line, the seabed as a height
// field, and concrete blocks.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <functional>
#include <vector>

#include "auv/sim/worldgen/surface_grid.h"

namespace auv::sim::worldgen {

/// A rocky formation: a closed wall around a crest line (the "ridge"), leaning back as it rises
/// and rounding over into the crest, its surface displaced by fractal noise. Overhang-free by
/// construction (apart from the noise) unless `width_profile` says otherwise; its
/// cross-section at a depth is a closed curve.
struct RockSpec {
  std::vector<Eigen::Vector2f> ridge;  ///< crest line, mesh xy (m), smooth and densely sampled;
                                       ///< a single point makes a round boulder
  /// Half-width (m) at seabed level, from the ridge along its normal, at ridge arc length
  /// `along` (m) on `side` (+1 left of the ridge direction, -1 right).
  std::function<float(float along, int side)> half_width;
  float seabed_z = -10.0f;  ///< m, the height the half-width refers to
  float bottom_z = -11.0f;  ///< m, lowest row (buried below the seabed)
  float top_z = 1.0f;       ///< m, height of the crest line
  float crest = 0.3f;       ///< fraction of seabed_z..top_z taken by the rounded crest
  float taper = 0.35f;      ///< fraction of the half-width lost from the seabed to the crest
  float roughness = 0.5f;   ///< m, largest displacement of the surface along its normal
  /// If set, replaces the crest/taper profile: the half-width at height z (bottom_z..top_z) as
  /// a fraction of `half_width`, 0 at top_z; may grow with z (a face leaning out, overhanging).
  std::function<float(float z)> width_profile;
  /// If set, the largest displacement (m, at most `roughness`) at a mesh xy point (e.g. small
  /// where a passage's width is designed); should vary smoothly.
  std::function<float(const Eigen::Vector2f& xy)> roughness_at;
  float spacing = 0.25f;     ///< m, grid spacing
  float texel_size = 0.02f;  ///< m
  uint64_t seed = 1;         ///< displacement noise
};

/// Half-width at height z as a fraction of the seabed half-width: 1 at seabed_z, falling
/// linearly by `taper` up to the crest, then elliptically to 0 at top_z (before roughness).
float rockWidthFraction(const RockSpec& spec, float z);

/// The rock's wall and crest as one closed band (bottom open, buried).
SurfaceGrid buildRock(const RockSpec& spec);

/// Distance (m) from `point` to the polyline `line` (mesh xy).
float distanceToPolyline(const std::vector<Eigen::Vector2f>& line, const Eigen::Vector2f& point);

/// The seabed: a gently undulating height field.
struct SeabedSpec {
  Eigen::AlignedBox2f area;  ///< mesh xy extent (m)
  float mean_z = -10.0f;     ///< m, mean height (negative: below the surface)
  float undulation = 0.4f;   ///< m, amplitude of the large-scale relief
  float spacing = 0.75f;     ///< m, grid spacing
  float texel_size = 0.05f;  ///< m
  uint64_t seed = 1;
  /// True where something solid hides the seabed (those quads are left out); may be empty.
  std::function<bool(const Eigen::Vector2f&)> covered;
};

/// Seabed height (m, mesh z) at mesh (x, y).
float seabedHeight(const SeabedSpec& spec, float x, float y);
SurfaceGrid buildSeabed(const SeabedSpec& spec);

/// The four walls and the top of an axis-aligned block (no bottom: it stands buried).
std::vector<SurfaceGrid> buildBlock(const Eigen::AlignedBox3f& box, float spacing,
                                    Material material, float texel_size);

}  // namespace auv::sim::worldgen
