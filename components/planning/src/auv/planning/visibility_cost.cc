#include "auv/planning/visibility_cost.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <ompl/base/SpaceInformation.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>

namespace auv::planning {

void VisibilityCostOptions::check() const {
  if (!(expected_distance > 0.0)) {
    throw PlanningConfigError("visibility cost: expected_distance (d_e) must be > 0, got " +
                              std::to_string(expected_distance));
  }
  if (!(admissible_range >= 0.0 && admissible_range < 2.0 * expected_distance)) {
    throw PlanningConfigError(
        "visibility cost: admissible_range (Δd_a) must be in [0, 2 d_e), got " +
        std::to_string(admissible_range));
  }
}

double visibilityCost(double distance, const VisibilityCostOptions& options) {
  const double d_e = options.expected_distance;
  const double half_range = 0.5 * options.admissible_range;
  double cost = 0.0;
  if (distance < d_e - half_range) {
    cost = (1.0 - distance / d_e) * kMaxVisibilityCost;
  } else if (distance > d_e + half_range) {
    cost = (distance / d_e - 1.0) * kMaxVisibilityCost;
  }
  return std::clamp(cost, 0.0, kMaxVisibilityCost);
}

void VisibilityObjectiveOptions::check() const {
  cost.check();
  if (!(visibility_weight >= 0.0)) {
    throw PlanningConfigError("visibility objective: visibility_weight must be >= 0, got " +
                              std::to_string(visibility_weight));
  }
  if (!std::isfinite(integration_step)) {
    throw PlanningConfigError("visibility objective: integration_step must be finite");
  }
}

Eigen::Vector3d statePosition(const ompl::base::State* state) {
  const auto* values = state->as<ompl::base::RealVectorStateSpace::StateType>()->values;
  return {values[0], values[1], values[2]};
}

VisibilityObjective::VisibilityObjective(const ompl::base::SpaceInformationPtr& si,
                                         std::shared_ptr<const DistanceField> field,
                                         const VisibilityObjectiveOptions& options)
    : ompl::base::OptimizationObjective(si), field_(std::move(field)), options_(options) {
  if (!field_) throw PlanningConfigError("visibility objective: null distance field");
  options_.check();
  step_ = options_.integration_step > 0.0 ? options_.integration_step : field_->resolution();
  description_ = "Path length weighted by visibility cost (Eq. 1)";
  setCostToGoHeuristic(&ompl::base::goalRegionCostToGo);
}

double VisibilityObjective::costDensity(const Eigen::Vector3d& position) const {
  return 1.0 + options_.visibility_weight *
                   visibilityCost(field_->distance(position), options_.cost) / kMaxVisibilityCost;
}

ompl::base::Cost VisibilityObjective::stateCost(const ompl::base::State* state) const {
  return ompl::base::Cost(costDensity(statePosition(state)));
}

ompl::base::Cost VisibilityObjective::motionCost(const ompl::base::State* from,
                                                 const ompl::base::State* to) const {
  const Eigen::Vector3d start = statePosition(from);
  const Eigen::Vector3d end = statePosition(to);
  const double length = (end - start).norm();
  if (length <= 0.0) return identityCost();
  if (options_.visibility_weight == 0.0) return ompl::base::Cost(length);
  const int segments = std::max(1, static_cast<int>(std::ceil(length / step_)));
  double previous = costDensity(start);
  double integral = 0.0;
  for (int i = 1; i <= segments; ++i) {
    const double next = costDensity(start + (end - start) * (static_cast<double>(i) / segments));
    integral += 0.5 * (previous + next);
    previous = next;
  }
  return ompl::base::Cost(integral * length / segments);
}

ompl::base::Cost VisibilityObjective::motionCostHeuristic(const ompl::base::State* from,
                                                          const ompl::base::State* to) const {
  return ompl::base::Cost((statePosition(to) - statePosition(from)).norm());
}

}  // namespace auv::planning
