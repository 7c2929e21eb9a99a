#pragma once
// Solid (3D) procedural textures for the generated worlds: the colour is a function of the
// point in space, not of texture coordinates, so a steep rock wall is as detailed as a flat
// seabed and neighbouring atlas cells match at their seams. Each material is built to give
// feature detectors (SIFT) many distinct blobs and corners at 1-2 cm/texel: multi-scale
// colour variation, mineral grain, cracks, pits and encrusting life.

#include <Eigen/Core>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>

#include "auv/sim/worldgen/noise.h"

namespace auv::sim::worldgen {

enum class Material {
  ROCK,      ///< granite-like rock with cracks, coralline and turf algae, sponges
  CONCRETE,  ///< harbour concrete: aggregate, bugholes, lift joints, rust streaks, algae
  SAND,      ///< rippled sand with shell grit and seagrass patches
};

std::string materialName(Material material);

/// Slowly varying fields of a material at a point (tone, large patches, the noise behind long
/// cracks): smooth over several texels, so the baker evaluates them on a coarser grid and
/// interpolates, which keeps a 4096^2 atlas to a few seconds.
struct CoarseFields {
  static constexpr int kCount = 7;
  float value[kCount] = {0, 0, 0, 0, 0, 0, 0};
};

class MaterialShader {
 public:
  /// Every material's pattern is drawn from `seed`: same seed, same colours.
  explicit MaterialShader(uint64_t seed);

  /// sRGB colour (R, G, B in [0, 1]) of `material` at `point` (m, mesh frame: z up, z = 0 the
  /// sea surface) on a surface with unit `normal`. `texel_size` (m) is the spacing it will be
  /// sampled at: detail finer than about two texels is left out rather than aliased.
  Eigen::Vector3f shade(Material material, const Eigen::Vector3f& point,
                        const Eigen::Vector3f& normal, float texel_size) const {
    return shadeFine(material, point, normal, texel_size, coarse(material, point, normal));
  }

  /// The slowly varying fields at `point` (wavelengths of 0.5 m and more).
  CoarseFields coarse(Material material, const Eigen::Vector3f& point,
                      const Eigen::Vector3f& normal) const;
  /// The colour given the coarse fields at (or interpolated to) `point`.
  Eigen::Vector3f shadeFine(Material material, const Eigen::Vector3f& point,
                            const Eigen::Vector3f& normal, float texel_size,
                            const CoarseFields& coarse) const;

 private:
  Eigen::Vector3f rock(const Eigen::Vector3f& p, const Eigen::Vector3f& n, float texel,
                       const CoarseFields& f) const;
  Eigen::Vector3f concrete(const Eigen::Vector3f& p, const Eigen::Vector3f& n, float texel,
                           const CoarseFields& f) const;
  Eigen::Vector3f sand(const Eigen::Vector3f& p, const Eigen::Vector3f& n, float texel,
                       const CoarseFields& f) const;

  GradientNoise colour_;  ///< large-scale colour variation
  GradientNoise relief_;  ///< small height field lit from above (embossed look)
  GradientNoise grain_;   ///< mineral grain, aggregate, grit
  GradientNoise cracks_;  ///< cracks and joints
  GradientNoise life_;    ///< algae, sponges, barnacles, seagrass
};

/// A `size` x `size` BGR image of `material` sampled every `texel_size` metres on a plane: a
/// vertical wall facing north through `origin` (rows going down in depth) when `vertical`,
/// else the horizontal plane z = origin.z. For tests and documentation.
cv::Mat renderMaterialSample(Material material, uint64_t seed, float texel_size, int size,
                             bool vertical = true,
                             const Eigen::Vector3f& origin = Eigen::Vector3f(0, 0, -2));

}  // namespace auv::sim::worldgen
