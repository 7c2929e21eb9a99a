#pragma once
// A synthetic site seen twice, for the change tests and benchmarks (as COLMAP keeps its
// synthetic scenes in the library): a rolling seabed 20 × 20 m (NED, z down, around 20 m
// depth) sampled every `spacing_m` with 5 mm noise, coloured like sand and rock; the changed
// epoch adds a 1 m block on x ∈ (2, 5), y ∈ (1, 4), 0.3 m of growth on x ∈ (−6, −2),
// y ∈ (−6, −2) and a bleached patch (colour only) on x ∈ (−6, −2), y ∈ (3, 7), and is filmed
// in other light (every colour through a per-channel gain and offset).
#include <filesystem>

#include <Eigen/Core>

namespace auv::recon::change {

struct SyntheticSurvey {
  bool changed = false;                              ///< with the block and the growth
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  ///< m, the survey's own frame
  unsigned seed = 1;                                 ///< of the noise
  double spacing_m = 0.1;
  bool with_mesh = false;  ///< also mesh/mesh.ply: the sample grid's triangles
};

bool onSyntheticBlock(double x, double y);
bool onSyntheticGrowth(double x, double y);
bool onSyntheticBleaching(double x, double y);

/// Writes `root`/dense/fused.ply (and mesh/mesh.ply).
void writeSyntheticSurvey(const std::filesystem::path& root, const SyntheticSurvey& survey);

}  // namespace auv::recon::change
