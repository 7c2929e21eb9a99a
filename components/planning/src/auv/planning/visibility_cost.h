// The visibility costmap of Eq. (1) (docs/paper.md §2.4) and an OMPL objective that combines it
// with path length. High cost steers the planner away but never forbids a path (narrow passages
// stay admissible): validity is decided by MapValidityChecker alone.
#pragma once

#include <memory>

#include <ompl/base/OptimizationObjective.h>

#include "auv/planning/distance_field.h"

namespace auv::planning {

struct VisibilityCostOptions {
  /// m, d_e: the expected (camera) distance to the inspected structure.
  double expected_distance = 3.0;
  /// m, Δd_a: width of the admissible interval [d_e - Δd_a/2, d_e + Δd_a/2] where the cost is 0.
  double admissible_range = 1.0;

  /// Throws PlanningConfigError: d_e > 0, 0 <= Δd_a < 2 d_e.
  void check() const;
};

/// Maximum of Eq. (1): the paper bounds the cost to [0, 100].
constexpr double kMaxVisibilityCost = 100.0;

/// Eq. (1): (1 - d/d_e)·100 below the admissible interval, 0 inside it (edges included),
/// (d/d_e - 1)·100 above it; clamped to [0, 100] (the far branch exceeds 100 past 2 d_e).
double visibilityCost(double distance, const VisibilityCostOptions& options);

struct VisibilityObjectiveOptions {
  VisibilityCostOptions cost;
  /// Weight w of the visibility term: a metre at cost 100 counts as (1 + w) metres; w = 0
  /// gives plain path length.
  double visibility_weight = 1.0;
  /// m, integration step along a motion; <= 0 means the distance field resolution.
  double integration_step = 0.0;

  void check() const;
};

/// Motion cost = ∫ (1 + w · Cost(d(s)) / 100) ds along the straight segment (trapezoid rule at
/// `integration_step`). The integrand is >= 1, so Euclidean length is an admissible heuristic
/// (used for motionCostHeuristic and the cost-to-go of goal regions). stateCost() returns the
/// integrand at a state. Position = the first three coordinates of a RealVectorStateSpace.
class VisibilityObjective : public ompl::base::OptimizationObjective {
 public:
  VisibilityObjective(const ompl::base::SpaceInformationPtr& si,
                      std::shared_ptr<const DistanceField> field,
                      const VisibilityObjectiveOptions& options);

  ompl::base::Cost stateCost(const ompl::base::State* state) const override;
  ompl::base::Cost motionCost(const ompl::base::State* from,
                              const ompl::base::State* to) const override;
  ompl::base::Cost motionCostHeuristic(const ompl::base::State* from,
                                       const ompl::base::State* to) const override;

  /// 1 + w·Cost(d)/100 at `position`.
  double costDensity(const Eigen::Vector3d& position) const;
  const VisibilityObjectiveOptions& options() const { return options_; }

 private:
  std::shared_ptr<const DistanceField> field_;
  VisibilityObjectiveOptions options_;
  double step_;
};

/// Position of a RealVectorStateSpace state with >= 3 dimensions (NED).
Eigen::Vector3d statePosition(const ompl::base::State* state);

}  // namespace auv::planning
