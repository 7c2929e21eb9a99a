#pragma once
// A site that changes between visits: the scenario's `changes:` list, applied to the world mesh
// when it is loaded, so that a later visit of the same site sees a block moved or removed, a
// new rock, a patch grown or eroded, or a patch whose colour changed (format:
// components/simulator/README.md, "Sites that change"). What each change did to the mesh is
// kept (AppliedChange) for the ground truth (change_truth.h).

#include <Eigen/Core>
#include <string>
#include <vector>

#include "auv/sim/common/yaml_section.h"
#include "auv/sim/world/mesh.h"

namespace auv::sim {

enum class SiteChangeType { kAdd, kRemove, kMove, kGrow, kAlbedo };

const char* toString(SiteChangeType type);

/// One entry of `changes:`. Positions are world NED (m), after the mesh is placed.
struct SiteChange {
  std::string name;
  SiteChangeType type = SiteChangeType::kGrow;
  /// add: where the new rock's base sits (a point on the surface); the others: the centre of
  /// the sphere the change acts in (remove/move: the loose rocks lying wholly inside it).
  Eigen::Vector3d center{0, 0, 0};
  double radius = 1.0;                     ///< m (grow, albedo, remove, move)
  Eigen::Vector3d size{1.0, 0.7, 0.5};     ///< m, add: length, width, height of the rock
  Eigen::Vector3d translation{0, 0, 0};    ///< m, move
  double yaw_deg = 0.0;                    ///< deg, add: heading of the rock; move: turn
  double thickness = 0.2;                  ///< m, grow: > 0 grows, < 0 erodes
  Eigen::Vector3d color{0.85, 0.85, 0.8};  ///< sRGB [0, 1], albedo: the new colour
  double strength = 0.7;                   ///< albedo: blend towards `color`, (0, 1]
  int seed = 1;                            ///< add: shape of the rock
};

/// Reads `changes:` (a list; absent = none). Throws ConfigError naming the file, the entry
/// and the field.
std::vector<SiteChange> readSiteChanges(const YamlSection& root);

/// A sphere that bounds where a change acted (world NED).
struct ChangeSupport {
  Eigen::Vector3d center{0, 0, 0};
  double radius = 0.0;
};

/// What one change did: where (the truth samples the surfaces there), and, for a growth, the
/// volume it added or removed (exact for the displaced triangles).
struct AppliedChange {
  SiteChange change;
  std::vector<ChangeSupport> supports;  ///< move: [from, to]; the others one
  double displaced_volume_m3 = 0.0;     ///< grow: signed volume between the surfaces
};

/// Applies `changes` in order to `mesh` (already in the world frame). Throws ConfigError
/// naming `file` and the entry when a change cannot apply (remove/move with no loose rock
/// inside its sphere, a growth on no surface).
std::vector<AppliedChange> applySiteChanges(Mesh& mesh, const std::vector<SiteChange>& changes,
                                            const std::string& file);

/// The parts of `mesh` that are loose rocks: connected sets of triangles (through shared
/// vertices) whose vertices all lie within `radius` of `center`.
std::vector<std::vector<int>> looseRocksWithin(const Mesh& mesh, const Eigen::Vector3d& center,
                                               double radius);

}  // namespace auv::sim
