#pragma once
// Step 1 of dense matching (docs/paper.md §3.5): for each master image, the neighbouring images
// it is matched against, chosen from the sparse model by co-visibility (shared sparse points) and
// triangulation angle, and the master's depth range from the sparse points it sees.

#include <cstdint>
#include <vector>

#include "auv/recon/scene/reconstruction.h"

namespace auv::recon::dense {

struct NeighbourOptions {
  int max_neighbours = 4;          ///< images matched against each master
  int min_shared_points = 10;      ///< sparse points a neighbour must share with the master
  double min_angle_deg = 1.5;      ///< median triangulation angle of the shared points, deg
  double max_angle_deg = 50.0;     ///< larger angles: views too different to correlate, deg
  double good_angle_deg = 8.0;     ///< angles below this are down-weighted in the score, deg
  double depth_percentile = 0.02;  ///< fraction of the master's sparse depths cut at each end
  double depth_margin = 0.25;      ///< the depth range widened by this fraction at each end
  int min_depth_points = 8;        ///< sparse points the master must see for a depth range

  /// Throws OptionError naming the field and value.
  void check() const;
};

/// A master image, its neighbours (best first) and its depth range.
struct MasterSelection {
  uint32_t master = 0;
  std::vector<uint32_t> neighbours;
  std::vector<int> shared_points;       ///< per neighbour
  std::vector<double> angle_deg;        ///< per neighbour: median triangulation angle
  double depth_min = 0, depth_max = 0;  ///< model units; 0 when too few points
  size_t depth_points = 0;              ///< sparse points the master sees in front of it

  bool usable() const { return !neighbours.empty() && depth_max > depth_min && depth_min > 0; }
};

/// One entry per registered image, in image id order. Score of a candidate: shared points x
/// min(1, angle / good_angle)^2, candidates outside [min_angle, max_angle] or with fewer than
/// min_shared_points shared points excluded.
std::vector<MasterSelection> selectNeighbours(const scene::Reconstruction& model,
                                              const NeighbourOptions& options);

}  // namespace auv::recon::dense
