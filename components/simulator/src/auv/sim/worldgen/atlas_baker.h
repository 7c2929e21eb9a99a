#pragma once
// Turns the surface grids of a generated world into one textured Mesh: the world keeps a single
// texture image, so every patch of quads gets its own cell of a texture atlas, sized by the
// patch's real extent (uniform texel density on steep walls too, no stretched planar
// projection), and the cell is filled by evaluating the patch's solid material at the 3D point
// of every texel.

#include <cstdint>
#include <vector>

#include "auv/sim/world/mesh.h"
#include "auv/sim/worldgen/surface_grid.h"

namespace auv::sim::worldgen {

struct AtlasOptions {
  int max_texture_size = 4096;    ///< px, the atlas's longest side; texels grow to fit in it
  int max_cell_size = 512;        ///< px, largest cell side; bigger patches are split
  int padding = 2;                ///< px of border around each cell, so filtering never bleeds
  int coarse_step = 4;            ///< px between evaluations of a material's slow fields
  float dry_texel_factor = 4.0f;  ///< texels this much coarser where a patch lies wholly above
                                  ///< the sea surface (z > 0), which no underwater camera sees
  uint64_t seed = 1;              ///< seed of the material patterns

  /// Throws ConfigError naming the field.
  void check() const;
};

struct AtlasReport {
  int texture_width = 0;     ///< px
  int texture_height = 0;    ///< px
  float texel_scale = 1.0f;  ///< every surface's texel_size was multiplied by this to fit
  size_t cells = 0;          ///< atlas cells (patches)
  double fill = 0.0;         ///< fraction of the atlas covered by cells
};

/// One mesh (mesh frame, as the grids) with per-corner texture coordinates and the baked atlas
/// (BGR). Degenerate triangles (collapsed crests) and disabled quads are left out. The result
/// depends only on the grids and options (parallel baking writes disjoint cells).
Mesh bakeTexturedMesh(const std::vector<SurfaceGrid>& grids, const AtlasOptions& options,
                      AtlasReport* report = nullptr);

}  // namespace auv::sim::worldgen
