#pragma once
// The texturing of docs/paper.md §3.7 after Waechter, Moehrle and Goesele, "Let There Be
// Color! Large-Scale Texturing of 3D Reconstructions", ECCV 2014: view selection (visibility,
// GMI data term, photo-consistency rejection, Potts MRF by alpha-expansion), global seam
// levelling, local seam blending, atlas packing. README.md lists every option.

#include <vector>

#include "auv/recon/texture/atlas.h"
#include "auv/recon/texture/seam_leveling.h"
#include "auv/recon/texture/textured_model.h"
#include "auv/recon/texture/view_selection.h"

namespace auv::recon::texture {

struct TextureOptions {
  ViewSelectionOptions selection;
  bool global_leveling = true;  ///< false: no seam levelling (for comparison)
  SeamLevelingOptions leveling;
  AtlasOptions atlas;

  void check() const {
    selection.check();
    leveling.check();
    atlas.check();
  }
};

struct TextureStats {
  size_t faces = 0, faces_seen = 0, faces_unseen = 0;
  size_t views = 0, views_used = 0;
  size_t observations = 0, rejected_observations = 0;  ///< (face, view) pairs
  double greedy_energy = 0, energy = 0;
  size_t greedy_seams = 0, seams = 0;
  int cycles = 0;
  SeamLevelingResult leveling;  ///< without its offsets
  AtlasStats atlas;
  double seconds_visibility = 0, seconds_selection = 0, seconds_leveling = 0, seconds_atlas = 0;
};

struct TextureResult {
  TexturedModel model;
  std::vector<int> labels;  ///< view per face, kNoLabel for unseen faces
  std::vector<std::vector<FaceObservation>> observations;  ///< after photo-consistency
  TextureStats stats;
};

/// Textures `mesh` from `views`; `masks` (optional, observeFaces): masked pixels give no
/// colour. Throws StageError("texture", ...) for an empty mesh, no views, or when no view sees
/// any face.
TextureResult textureMesh(const FaceMesh& mesh, const std::vector<ViewGeometry>& views,
                          const ImageLoader& images, const TextureOptions& options,
                          const ImageLoader& masks = nullptr);

}  // namespace auv::recon::texture
