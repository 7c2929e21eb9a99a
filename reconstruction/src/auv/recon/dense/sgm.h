#pragma once
// Semi-global aggregation of a matching cost over 1D paths (Hirschmueller, PAMI 2008, eq. 13:
// L_r(p, d) = C(p, d) + min(L_r(p-r, d), L_r(p-r, d +- 1) + P1, min_i L_r(p-r, i) + P2)
//         - min_i L_r(p-r, i)), on a label volume whose per-pixel label ranges differ
// (coarse-to-fine search as in Rothermel et al.'s tSGM, 2012: each pixel searches only an
// interval of the global label grid that the coarser level left open). Labels of neighbouring
// pixels are compared in the global grid; a label outside the previous pixel's interval costs
// as if it were a jump (P2).

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

namespace auv::recon::dense {

/// Matching costs are integers in [0, kMaxCost]: kCostScale per unit of (1 - NCC).
constexpr int kCostScale = 512;
constexpr int kMaxCost = 2 * kCostScale;

/// Costs of every pixel over its own interval of labels [low, low + count) of a global grid.
struct LabelVolume {
  int width = 0, height = 0;
  int stride = 0;               ///< maximum labels per pixel (storage per pixel)
  std::vector<int32_t> low;     ///< first label of each pixel's interval
  std::vector<uint16_t> count;  ///< labels in each pixel's interval (0: pixel not matched)
  std::vector<uint16_t> cost;   ///< width * height * stride

  void reset(int width, int height, int stride);
  size_t pixels() const { return static_cast<size_t>(width) * height; }
  uint16_t* costs(size_t pixel) { return cost.data() + pixel * stride; }
  const uint16_t* costs(size_t pixel) const { return cost.data() + pixel * stride; }
};

struct SgmPenalties {
  int p1 = 24;               ///< cost units, a change of one label between neighbours
  int p2 = 160;              ///< cost units, a larger change (depth discontinuity)
  double p2_edge_grey = 10;  ///< P2 / (1 + |I(p) - I(p-r)| / this): jumps cheaper across edges
  int directions = 8;        ///< 4 (horizontal, vertical) or 8 (and diagonals)
};

/// Sums of the path costs over all directions, `volume.stride` values per pixel (same layout
/// as volume.cost). `guide`: the master image (CV_32F, same size) for the edge-aware P2. The
/// two half-passes (4 directions each) run in parallel with OpenMP.
std::vector<uint16_t> aggregatePaths(const LabelVolume& volume, const cv::Mat& guide,
                                     const SgmPenalties& penalties);

}  // namespace auv::recon::dense
