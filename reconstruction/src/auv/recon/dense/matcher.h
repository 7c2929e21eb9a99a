#pragma once
// Step 2 of dense matching (docs/paper.md §3.5): the depth map of a master image by semi-global
// multi-image matching in the manner of MicMac (Pierrot-Deseilligny & Paparoditis 2006, the
// paper's refs. [70,71]), coarse to fine over an image pyramid:
//  * hypotheses: depths sampled uniformly in inverse depth (one label ~ label_px of epipolar
//    displacement in the widest-baseline neighbour) over the depth range the sparse points
//    give;
//  * cost: normalised cross-correlation of a (2r+1)^2 window of the master with each
//    neighbour resampled at the hypothesis (fronto-parallel at the coarsest level, following
//    the coarser level's surface at the finer ones), aggregated over the neighbours as
//    1 - mean of the best k (occlusion-robust);
//  * regularisation: SGM path aggregation (sgm.h, Hirschmueller's P1/P2);
//  * coarse to fine: each level searches, per pixel, only the labels around what the coarser
//    level found in its 3x3 neighbourhood (tSGM-style dynamic ranges);
//  * winner-take-all with parabolic sub-label refinement; a depth is kept when its NCC, its
//    uniqueness and its place inside the searched interval are good, then speckles are removed.

#include <vector>

#include <opencv2/core.hpp>

#include "auv/recon/dense/sgm.h"
#include "auv/recon/dense/view.h"

namespace auv::recon::dense {

struct MatcherOptions {
  int pyramid_levels = 4;         ///< levels including the finest; the coarsest is 1/2^(n-1)
  int min_level_size = 48;        ///< px: coarser levels whose longer side is below are skipped
  int window_radius = 3;          ///< NCC window (2r+1)^2 px, at every level
  int best_k = 2;                 ///< the cost averages the k best neighbours' NCC
  double label_px = 1.0;          ///< px of epipolar displacement per depth label
  int max_labels = 256;           ///< labels of the coarsest level's full search (cap)
  int search_labels = 12;         ///< labels per pixel at the finer levels
  int range_margin = 2;           ///< labels added at each end of a range from the coarser level
  int p1 = 24;                    ///< SGM penalty, cost units (512 = 1 unit of 1 - NCC)
  int p2 = 160;                   ///< SGM penalty for jumps, cost units
  double p2_edge_grey = 10;       ///< grey levels: P2 / (1 + |dI| / this) across edges
  int directions = 8;             ///< SGM paths: 4 or 8
  double min_ncc = 0.35;          ///< a final depth needs this aggregated NCC
  double uniqueness = 0.03;       ///< second-best aggregated cost (beyond +-1 label) must exceed
                                  ///< the best by this fraction
  double min_texture_grey = 1.0;  ///< std of the master window, grey levels: less is not matched
  int speckle_size = 50;          ///< px at the finest level: smaller isolated blobs are removed
  int speckle_labels = 2;         ///< labels: depth step that separates speckle blobs
  int strip_rows = 32;            ///< rows per cost strip (strips run in parallel)

  void check() const;
};

struct DepthMapResult {
  cv::Mat depth;       ///< CV_32F, model units; 0 where no depth
  cv::Mat confidence;  ///< CV_32F, the aggregated NCC at the chosen depth (0 where no depth)
  std::vector<int> labels_per_level;  ///< global labels, coarsest first
  std::vector<cv::Size> level_sizes;  ///< coarsest first
  size_t valid_pixels = 0;
  size_t hypotheses = 0;  ///< pixel-label costs computed over all levels
  double seconds_cost = 0, seconds_sgm = 0;
};

/// The depth map of `master` (at its size) against `neighbours` (images loaded, any size),
/// over [depth_min, depth_max]. Throws std::invalid_argument for a bad range or missing images.
DepthMapResult computeDepthMap(const View& master, const std::vector<View>& neighbours,
                               double depth_min, double depth_max, const MatcherOptions& options);

}  // namespace auv::recon::dense
