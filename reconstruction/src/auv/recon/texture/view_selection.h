#pragma once
// Per-face view selection of Waechter, Moehrle and Goesele, "Let There Be Color! Large-Scale
// Texturing of 3D Reconstructions", ECCV 2014, section 3 (docs/paper.md §3.7):
//  * visibility of each face in each view (inside the image, facing the camera, not hidden by
//    the mesh itself: z-buffer),
//  * data term: the gradient magnitude integral over the face's projection (GMI, section 3.1),
//    which favours close, orthogonal, in-focus, high-resolution views,
//  * photo-consistency check (section 3.2): views whose colour of the face disagrees with the
//    mode found by mean-shift over all views' colours (occluders: fish, particles) are dropped,
//  * labelling by an MRF with a Potts smoothness term between adjacent faces, minimised by
//    alpha-expansion (mrf.h).

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "auv/recon/texture/mrf.h"
#include "auv/recon/texture/rasterizer.h"

namespace auv::recon::texture {

/// The mesh the texturing works on (positions, triangles, one normal per face pointing out of
/// the surface, towards the cameras).
struct FaceMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> faces;
  std::vector<Eigen::Vector3d> face_normals;

  /// Face normals from the winding; where vertex normals are given, oriented like them.
  void computeFaceNormals(const std::vector<Eigen::Vector3d>& vertex_normals = {});
  /// Pairs of faces sharing an edge (each pair once).
  std::vector<std::pair<int, int>> faceAdjacency() const;
};

/// One view's observation of one face.
struct FaceObservation {
  int view = 0;
  float quality = 0;  ///< GMI: sum of (|grad I| + floor) over the face, px
  float area_px = 0;  ///< projected area, px^2
  Eigen::Vector3f mean_color = Eigen::Vector3f::Zero();  ///< BGR, 0..255
};

struct ViewSelectionOptions {
  /// Faces seen at a grazing angle are not textured from that view: cos(angle between the face
  /// normal and the direction to the camera) must exceed this.
  double min_view_cosine = 0.1;
  /// Occlusion test tolerance: a face point is visible when its depth is within this fraction
  /// of the z-buffer depth.
  double depth_tolerance = 0.01;
  /// Pixels kept clear of the image border (the projection must lie inside by this much), px.
  double border_px = 1.0;
  /// Added to the gradient magnitude (grey levels per px) in the GMI, so that in textureless
  /// areas the view with the larger projection still wins.
  double gradient_floor = 1.0;
  /// "gmi" (Waechter's gradient magnitude integral) or "area" (projected area alone).
  std::string data_term = "gmi";
  /// Photo-consistency rejection (Waechter section 3.2); needs at least this many views.
  bool photo_consistency = true;
  int photo_consistency_min_views = 3;
  /// Mean-shift kernel bandwidth floor (colour units 0..255): the per-face bandwidth is the
  /// robust spread (1.4826 MAD) of the views' colours, never below this.
  double photo_consistency_sigma = 10.0;
  /// A view is rejected when its Gaussian kernel weight at the mode falls below this
  /// (Waechter et al. use 6e-3).
  double photo_consistency_threshold = 6e-3;
  /// Potts weight of a label change between adjacent faces, in units of the data cost (which
  /// is 1 - quality / best quality of the face, in [0, 1]).
  double smoothness = 0.5;
  /// Alpha-expansion cycles at most.
  int max_cycles = 8;
  /// false: greedy per-face pick (for comparison only).
  bool use_mrf = true;

  void check() const;
};

/// Source of the view images (BGR 8-bit), so that hundreds of views need not be in memory at
/// once.
using ImageLoader = std::function<cv::Mat(int view)>;

/// Per face, the views that see it with their quality and mean colour (sorted by view).
/// `masks` (optional): per view a CV_8U mask of the image's size, 0 where the image must give
/// no colour (masks/mask.h), or empty; a view does not observe a face that covers a masked
/// pixel, so no colour of the face comes from there.
std::vector<std::vector<FaceObservation>> observeFaces(const FaceMesh& mesh,
                                                       const std::vector<ViewGeometry>& views,
                                                       const ImageLoader& images,
                                                       const ViewSelectionOptions& options,
                                                       const ImageLoader& masks = nullptr);

/// Removes the observations whose colour is inconsistent with the face's other views
/// (mean-shift mode, Waechter section 3.2), after dividing each view's colours by its exposure
/// gain (median ratio to the per-face medians over all faces). Returns the number removed.
/// Faces with fewer than `photo_consistency_min_views` views are left alone.
size_t rejectInconsistentViews(std::vector<std::vector<FaceObservation>>& observations,
                               const ViewSelectionOptions& options);

/// The MRF of the labelling: data costs 1 - quality / (best quality of the face) per candidate.
PottsProblem buildLabelingProblem(const std::vector<std::vector<FaceObservation>>& observations,
                                  const std::vector<std::pair<int, int>>& adjacency,
                                  const ViewSelectionOptions& options);

struct ViewSelectionResult {
  std::vector<int> labels;  ///< view per face, kNoLabel when no view sees it
  double greedy_energy = 0, energy = 0;
  size_t greedy_seams = 0, seams = 0;
  int cycles = 0;
};

/// Labels the faces: greedy start, then alpha-expansion (unless options.use_mrf is false).
ViewSelectionResult selectViews(const std::vector<std::vector<FaceObservation>>& observations,
                                const std::vector<std::pair<int, int>>& adjacency,
                                const ViewSelectionOptions& options);

}  // namespace auv::recon::texture
