#pragma once
// Texture patches and their atlas (Waechter et al. ECCV 2014, sections 4-5): connected faces
// with the same view form a patch, cut from that view's image at its native resolution with a
// padding band, corrected by the seam-levelling offsets (interpolated over each face), feathered
// across seams (local blending, see README.md), and packed into square atlas pages with
// stb_rect_pack's skyline packer.

#include <vector>

#include "auv/recon/texture/seam_leveling.h"
#include "auv/recon/texture/textured_model.h"
#include "auv/recon/texture/view_selection.h"

namespace auv::recon::texture {

struct AtlasOptions {
  /// Largest atlas page side, texels (pages are square; a patch larger than a page is scaled).
  int max_page_size = 4096;
  /// Texel budget of the whole atlas, megatexels: patches are cut at the images' native
  /// resolution unless they add up to more, then all are scaled down by the same factor.
  double max_atlas_megapixels = 64.0;
  /// Texels of padding around each patch (bilinear filtering and mip-mapping read beyond the
  /// faces).
  int padding = 2;
  /// Local seam blending: colours within `blend_width` texels of a seam are feathered towards
  /// the other view's (levelled) colour, reaching their mean on the seam.
  bool local_blending = true;
  int blend_width = 6;
  /// Colour of the faces no view sees (BGR).
  int unseen_gray = 128;

  void check() const;
};

struct AtlasStats {
  size_t patches = 0, pages = 0;
  int page_size = 0;      ///< texels
  double fill_ratio = 0;  ///< patch texels / page texels
  size_t unseen_faces = 0;
  size_t blended_texels = 0;
  double texel_scale = 1.0;  ///< texels per source pixel (< 1 when over the budget)
};

struct AtlasResult {
  TexturedModel model;
  AtlasStats stats;
};

/// Builds the atlas and the textured model. `offsets` may be empty (no levelling). `images`
/// may be called from several threads at once.
AtlasResult buildAtlas(const FaceMesh& mesh, const std::vector<ViewGeometry>& views,
                       const std::vector<int>& labels,
                       const std::vector<std::vector<FaceObservation>>& observations,
                       const ColorOffsets& offsets, const ImageLoader& images,
                       const AtlasOptions& options);

/// Connected components of adjacent faces with the same label (unlabelled faces excluded):
/// patch index per face (-1 for unlabelled) and the number of patches.
std::pair<std::vector<int>, int> findPatches(const FaceMesh& mesh, const std::vector<int>& labels);

}  // namespace auv::recon::texture
