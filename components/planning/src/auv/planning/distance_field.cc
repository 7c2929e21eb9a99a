#include "auv/planning/distance_field.h"

#include <algorithm>
#include <limits>
#include <string>

#include <dynamicEDT3D/dynamicEDTOctomap.h>
#include <octomap/OcTree.h>

namespace auv::planning {

void OctomapDistanceFieldOptions::check() const {
  if (!(max_distance > 0.0)) {
    throw PlanningConfigError("distance field: max_distance must be > 0, got " +
                              std::to_string(max_distance));
  }
  for (int axis = 0; axis < 3; ++axis) {
    if (!(min_corner[axis] < max_corner[axis])) {
      throw PlanningConfigError("distance field: min_corner must be below max_corner on axis " +
                                std::to_string(axis));
    }
  }
}

OctomapDistanceField::OctomapDistanceField(octomap::OcTree* tree,
                                           const OctomapDistanceFieldOptions& options)
    : tree_(tree), options_(options) {
  if (tree_ == nullptr) throw PlanningConfigError("distance field: null OcTree");
  options_.check();
  const octomap::point3d min_corner(options_.min_corner.x(), options_.min_corner.y(),
                                    options_.min_corner.z());
  const octomap::point3d max_corner(options_.max_corner.x(), options_.max_corner.y(),
                                    options_.max_corner.z());
  constexpr bool kUnknownIsOccupied = false;  // delayed collision checking: unknown is free
  edt_ = std::make_unique<DynamicEDTOctomap>(static_cast<float>(options_.max_distance), tree_,
                                             min_corner, max_corner, kUnknownIsOccupied);
  edt_->update();
  ++revision_;
}

OctomapDistanceField::~OctomapDistanceField() = default;

void OctomapDistanceField::update() {
  edt_->update();
  ++revision_;
}

double OctomapDistanceField::distance(const Eigen::Vector3d& position) const {
  for (int axis = 0; axis < 3; ++axis) {
    if (position[axis] < options_.min_corner[axis] || position[axis] > options_.max_corner[axis]) {
      return options_.max_distance;
    }
  }
  float grid_distance = 0.0f;
  octomap::point3d obstacle;
  edt_->getDistanceAndClosestObstacle(octomap::point3d(position.x(), position.y(), position.z()),
                                      grid_distance, obstacle);
  if (grid_distance < 0.0f) return options_.max_distance;  // outside the grid: unknown, free
  if (grid_distance >= options_.max_distance) return options_.max_distance;
  // The grid measures between cell centres, off by up to a cell diagonal from what matters:
  // the surface seen lies somewhere in the occupied cell, the vehicle anywhere in its own.
  // The distance from the position itself to the obstacle cell's box is a lower bound.
  const double half = 0.5 * tree_->getResolution();
  const Eigen::Vector3d gap =
      ((position - Eigen::Vector3d(obstacle.x(), obstacle.y(), obstacle.z())).cwiseAbs().array() -
       half)
          .max(0.0);
  return std::min(gap.norm(), options_.max_distance);
}

double OctomapDistanceField::altitude(const Eigen::Vector3d& position, double reach) const {
  constexpr double kNone = std::numeric_limits<double>::infinity();
  octomap::OcTreeKey key;
  if (!(reach >= 0.0) ||
      !tree_->coordToKeyChecked(octomap::point3d(position.x(), position.y(), position.z()), key)) {
    return kNone;
  }
  // Down the column (z grows downwards in NED, as the tree's keys do) from the state's own
  // cell to the last cell whose top face is within reach.
  const double half = 0.5 * tree_->getResolution();
  for (octomap::key_type z = key[2];; ++z) {
    octomap::OcTreeKey cell = key;
    cell[2] = z;
    const double top = tree_->keyToCoord(z) - half;
    if (top - position.z() > reach) break;
    const octomap::OcTreeNode* node = tree_->search(cell);
    if (node != nullptr && tree_->isNodeOccupied(node)) return std::max(0.0, top - position.z());
    if (z == std::numeric_limits<octomap::key_type>::max()) break;
  }
  return kNone;
}

double OctomapDistanceField::resolution() const { return tree_->getResolution(); }

}  // namespace auv::planning
