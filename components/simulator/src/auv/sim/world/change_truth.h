#pragma once
// The true change of a site between two visits, measured between the world before and after
// the scenario's `changes:` (site_changes.h) — what `auv recon evaluate` scores a comparison of
// two surveys against. Written as ground_truth/changes.json (regions) and changes.ply (the
// changed-area mask with signed distances); the format is in components/simulator/README.md,
// "Sites that change".

#include <Eigen/Core>
#include <string>
#include <vector>

#include "auv/sim/world/mesh.h"
#include "auv/sim/world/scenario.h"
#include "auv/sim/world/site_changes.h"

namespace auv::sim {

struct ChangeTruthOptions {
  double spacing_m = 0.02;  ///< mean spacing of the surface samples
  double min_distance_m =
      0.01;  ///< samples closer than this to the other visit's surface: unchanged
  double max_distance_m = 5.0;  ///< farthest closest-point query
  double column_m = 0.02;       ///< grid of the vertical columns that measure block volumes
  uint32_t seed = 1;            ///< sample positions (the same inputs give the same files)
};

/// One changed region (a move gives two: where the rock was and where it is).
struct ChangeTruthRegion {
  std::string name;    ///< the change's name, `/from` and `/to` for a move
  std::string change;  ///< the change's name
  SiteChangeType type = SiteChangeType::kGrow;
  bool geometric = true;  ///< false for albedo
  Eigen::Vector3d centroid{0, 0, 0};
  double radius_m = 0.0;         ///< bounds the region's points around the centroid
  double area_m2 = 0.0;          ///< changed surface (samples x spacing^2)
  double mean_distance_m = 0.0;  ///< signed: + material gained in the later visit
  double max_distance_m = 0.0;   ///< signed, the largest magnitude
  double volume_gained_m3 = 0.0;
  double volume_lost_m3 = 0.0;
  size_t points = 0;
};

struct ChangeTruth {
  std::vector<ChangeTruthRegion> regions;
  std::vector<Eigen::Vector3f> points;  ///< world NED
  std::vector<float> distances;         ///< signed m (0 for albedo)
  std::vector<int> region_of_point;     ///< index into regions
};

/// Measures the change between `before` and `after` (both world frame) where `applied` acted:
/// samples of the later surface standing out of the earlier one (gained) and of the earlier
/// surface standing out of the later one (lost, negative distance). Volumes: vertical columns
/// between the two surfaces for add/remove/move (what a survey from above measures), the
/// displaced volume for a growth.
ChangeTruth measureChangeTruth(const Mesh& before, const Mesh& after,
                               const std::vector<AppliedChange>& applied,
                               const ChangeTruthOptions& options = {});

/// Writes `<dir>/changes.json` and `<dir>/changes.ply` (binary little-endian: float x y z,
/// float distance, int region), each through a temporary file renamed when complete.
void writeChangeTruth(const ChangeTruth& truth, const std::string& dir,
                      const std::string& scenario_name, const ChangeTruthOptions& options = {});

/// For a scenario with `changes:`: measures the true change and writes changes.json,
/// changes.ply and the later visit's world geometry `world.ply` (world frame, what the
/// evaluation measures a reconstruction of this visit against) into `dir`; `changes: []` gives
/// a truth with no regions (a control: every change found is false). Returns false (and
/// writes nothing) for a scenario without a `changes:` section.
bool writeScenarioChangeTruth(const Scenario& scenario, const std::string& dir,
                              const ChangeTruthOptions& options = {});

}  // namespace auv::sim
