#pragma once
// The simulator's truth of what changed at a site between two visits, as `auv sim render`
// writes it into the later visit's run (components/simulator/README.md, "Sites that change"):
//
//   <run>/ground_truth/changes.json  "auv-sim-changes 1": min_distance_m and the regions (a
//                                    move gives two, <change>/from lost and <change>/to gained)
//   <run>/ground_truth/changes.ply   points every ~2 cm on the changed surface: float x y z
//                                    (world NED, m), float distance (signed: + gained in the
//                                    later visit), int region (index into the regions)

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace auv::recon::evaluate {

/// One changed region of the truth.
struct TrueChangeRegion {
  std::string name;       ///< unique; "<change>/from", "<change>/to" for a move
  std::string change;     ///< the scenario's change it belongs to
  std::string type;       ///< add, remove, move, grow or albedo
  bool geometric = true;  ///< false for albedo (a colour change, no shape change)
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  ///< world NED, m
  double radius_m = 0;                                 ///< bounds its points around the centroid
  double area_m2 = 0;
  double mean_distance_m = 0;  ///< signed
  double max_distance_m = 0;   ///< signed, the largest magnitude
  double volume_gained_m3 = 0;
  double volume_lost_m3 = 0;
  size_t points = 0;  ///< its points in changes.ply

  double magnitude() const { return max_distance_m < 0 ? -max_distance_m : max_distance_m; }
  /// A block that appeared, went or moved: the volume goal (within 20 %) is for these.
  bool isBlock() const { return type == "add" || type == "remove" || type == "move"; }
};

struct ChangeTruth {
  std::filesystem::path json_file, ply_file;
  std::string scenario;
  double min_distance_m = 0;
  std::vector<TrueChangeRegion> regions;
  std::vector<Eigen::Vector3d> points;  ///< world NED, m
  std::vector<double> distances;        ///< signed m, 0 for albedo
  std::vector<int> region_of_point;     ///< index into regions
};

/// `<ground_truth_run>/ground_truth/changes.json` (the later visit's run).
std::filesystem::path changeTruthFile(const std::filesystem::path& ground_truth_run);

/// Reads changes.json and the changes.ply beside it. Throws StageError("evaluate", ...) naming
/// the file and the field (`changes.json: regions[2].type: ...`, `changes.ply: no vertex
/// property "region"`, a region index out of range, counts that disagree).
ChangeTruth readChangeTruth(const std::filesystem::path& json_file);

}  // namespace auv::recon::evaluate
