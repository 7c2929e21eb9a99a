// Distance to the nearest occupied cell: the `d` of the paper's Eq. (1) and of the clearance
// check. Unknown space counts as free (delayed collision checking, docs/paper.md §2.2.2).
#pragma once

#include <cstdint>
#include <memory>
#include <stdexcept>

#include <Eigen/Core>

namespace octomap {
class OcTree;
}
template <class TREE>
class DynamicEDTOctomapBase;

namespace auv::planning {

/// Thrown when options fail their check().
class PlanningConfigError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// A read-only distance query. Implementations must be safe to call from the planner thread
/// while nothing updates them (the caller serialises updates and queries).
class DistanceField {
 public:
  virtual ~DistanceField() = default;
  /// m, distance from `position` (NED) to the nearest occupied cell (to the cell's box, not its
  /// centre: a lower bound of the distance to what the sensor saw), clamped at maxDistance().
  /// Points outside the mapped volume are unknown, hence free: they return maxDistance().
  virtual double distance(const Eigen::Vector3d& position) const = 0;
  /// m, the distance reported when nothing occupied is nearer.
  virtual double maxDistance() const = 0;
  /// m, vertical distance from `position` (NED, z down) to the top face of the nearest known
  /// occupied cell directly below it (its column), 0 when its own cell is occupied; infinity
  /// when no occupied cell lies within `reach` below. Unknown cells do not count (free until
  /// seen): the min_altitude check of 3-D planning.
  virtual double altitude(const Eigen::Vector3d& position, double reach) const = 0;
  /// m, the grid step of the underlying map: motions are checked at half of it.
  virtual double resolution() const = 0;
  /// Increases every time the field changes, so users can tell a stale check from a fresh one.
  virtual std::uint64_t revision() const = 0;
};

struct OctomapDistanceFieldOptions {
  /// m, distances are clamped here; choose >= 2 d_e so Eq. (1) reaches its maximum far away.
  double max_distance = 10.0;
  /// m, NED corners of the volume the distance field covers (a dense grid at the map
  /// resolution: memory grows with its volume). Outside it everything counts as free.
  Eigen::Vector3d min_corner{-50.0, -50.0, 0.0};
  Eigen::Vector3d max_corner{50.0, 50.0, 30.0};

  /// Throws PlanningConfigError naming the offending field.
  void check() const;
};

/// DynamicEDT3D over an octomap::OcTree (incremental: update() reads the tree's changed keys).
/// The tree must outlive this object; its change detection is switched on here.
class OctomapDistanceField : public DistanceField {
 public:
  /// Builds the full field from `tree` (unknown = free). Throws PlanningConfigError.
  OctomapDistanceField(octomap::OcTree* tree, const OctomapDistanceFieldOptions& options);
  ~OctomapDistanceField() override;
  OctomapDistanceField(const OctomapDistanceField&) = delete;
  OctomapDistanceField& operator=(const OctomapDistanceField&) = delete;

  /// Folds the tree's changes since the last call into the field; bumps revision().
  void update();

  double distance(const Eigen::Vector3d& position) const override;
  double maxDistance() const override { return options_.max_distance; }
  /// Reads the tree's column (the tree as it is now, like update()).
  double altitude(const Eigen::Vector3d& position, double reach) const override;
  double resolution() const override;
  std::uint64_t revision() const override { return revision_; }

 private:
  octomap::OcTree* tree_;
  OctomapDistanceFieldOptions options_;
  std::unique_ptr<DynamicEDTOctomapBase<octomap::OcTree>> edt_;
  std::uint64_t revision_ = 0;
};

}  // namespace auv::planning
