#pragma once
// Global seam levelling (Waechter et al. ECCV 2014, section 4, after Lempitsky and Ivanov,
// "Seamless mosaicing of image-based texture maps", CVPR 2007): an additive colour offset g per
// (vertex, label) so that both sides of every seam agree and the offsets vary smoothly inside
// each patch:
//
//   argmin_g  sum_{seam vertices v, labels l != k at v} (f_vl + g_vl - f_vk - g_vk)^2
//           + smoothness * sum_{edges (v, u) of faces labelled l} (g_vl - g_ul)^2
//           + regularization * sum g^2
//
// f_vl is view l's colour at v, averaged along the seam edges adjacent to v (weighted towards
// v). One sparse least-squares problem (Eigen, normal equations, LDLT) shared by the three
// channels.

#include <cstdint>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "auv/recon/texture/view_selection.h"

namespace auv::recon::texture {

struct SeamLevelingOptions {
  /// Weight of the within-patch smoothness term relative to the seam term.
  double smoothness = 10.0;
  /// Weight pulling the offsets towards 0 (fixes the common offset the energy leaves free).
  double regularization = 1e-3;
  /// Samples per seam edge half (vertex to midpoint) for f_vl.
  int samples_per_edge = 5;

  void check() const;
};

/// A mesh edge between two faces with different (valid) labels.
struct SeamEdge {
  int v0 = 0, v1 = 0;          ///< vertices
  int face_a = 0, face_b = 0;  ///< the faces on either side
  int label_a = 0, label_b = 0;
};

/// Every seam edge of a labelling.
std::vector<SeamEdge> findSeamEdges(const FaceMesh& mesh, const std::vector<int>& labels);

struct ColorOffsets {
  /// Offset (BGR, 0..255 units) of vertex v in the patches of label l; zero when none.
  Eigen::Vector3f at(int vertex, int label) const;
  static uint64_t key(int vertex, int label) {
    return (static_cast<uint64_t>(static_cast<uint32_t>(vertex)) << 32) |
           static_cast<uint32_t>(label);
  }
  std::unordered_map<uint64_t, Eigen::Vector3f> offsets;
};

struct SeamLevelingResult {
  ColorOffsets offsets;
  size_t variables = 0, seam_edges = 0, seam_vertices = 0;
  /// Mean |f_vl - f_vk| over the seam terms before and after adding the offsets (0..255).
  double mean_jump_before = 0, mean_jump_after = 0;
};

/// Computes the offsets. `images` is called once per view that labels some face.
SeamLevelingResult levelSeams(const FaceMesh& mesh, const std::vector<ViewGeometry>& views,
                              const std::vector<int>& labels, const ImageLoader& images,
                              const SeamLevelingOptions& options);

}  // namespace auv::recon::texture
