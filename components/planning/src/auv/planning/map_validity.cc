#include "auv/planning/map_validity.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <ompl/base/spaces/RealVectorStateSpace.h>

#include "auv/planning/visibility_cost.h"

namespace auv::planning {
namespace ob = ompl::base;

const config::OptionTable<ClearanceOptions>& ClearanceOptions::table() {
  using config::Range;
  using O = ClearanceOptions;
  static const config::OptionTable<O> kTable = {
      {"hull_radius", &O::hull_radius, "radius of the sphere enclosing the hull", "m",
       Range::closed(0.0, 20.0)},
      {"safety_margin", &O::safety_margin, "clearance kept on top of hull_radius", "m",
       Range::closed(0.0, 20.0)},
      {"max_climb_angle", &O::max_climb_angle,
       "steepest climb of a path; keep below the forward sonar's upper half-aperture", "deg",
       Range::closed(1.0, 90.0)},
  };
  return kTable;
}

void ClearanceOptions::check() const {
  config::checkOptions<PlanningConfigError>(*this, table(), "clearance: ");
  if (!std::isfinite(motion_check_step)) {
    throw PlanningConfigError("clearance: motion_check_step must be finite");
  }
  if (!(min_altitude >= 0.0) || !std::isfinite(min_altitude)) {
    throw PlanningConfigError("clearance: min_altitude must be >= 0 m, got " +
                              std::to_string(min_altitude));
  }
}

void PlanningSpaceOptions::check() const {
  for (int axis = 0; axis < 3; ++axis) {
    if (!(min_corner[axis] < max_corner[axis])) {
      throw PlanningConfigError("planning space: min_corner must be below max_corner on axis " +
                                std::to_string(axis));
    }
  }
  if (fixed_depth && !(*fixed_depth >= min_corner.z() && *fixed_depth <= max_corner.z())) {
    throw PlanningConfigError("planning space: fixed_depth " + std::to_string(*fixed_depth) +
                              " outside [min_corner.z, max_corner.z]");
  }
}

MapValidityChecker::MapValidityChecker(const ob::SpaceInformationPtr& si,
                                       std::shared_ptr<const DistanceField> field,
                                       const ClearanceOptions& options)
    : ob::StateValidityChecker(si), field_(std::move(field)), options_(options) {
  if (!field_) throw PlanningConfigError("validity checker: null distance field");
  options_.check();
  specs_.clearanceComputationType = ob::StateValidityCheckerSpecs::EXACT;
}

bool MapValidityChecker::isValid(const ob::State* state) const {
  return si_->satisfiesBounds(state) && clearance(state) >= 0.0;
}

double MapValidityChecker::clearance(const ob::State* state) const {
  const Eigen::Vector3d position = statePosition(state);
  const double distance = field_->distance(position);
  return std::min(distance - options_.clearance(), altitudeMargin(position, distance));
}

double MapValidityChecker::altitudeMargin(const Eigen::Vector3d& position, double distance) const {
  constexpr double kNone = std::numeric_limits<double>::infinity();
  if (options_.min_altitude <= 0.0) return kNone;
  const double reach = options_.min_altitude + options_.clearance();
  // Nothing occupied within reach in any direction: the column is clear too (the cheap test
  // first; the column walk costs one octree search per cell).
  if (distance >= reach) return kNone;
  return field_->altitude(position, reach) - reach;
}

MapMotionValidator::MapMotionValidator(const ob::SpaceInformationPtr& si, double step,
                                       double max_climb_angle)
    : ob::MotionValidator(si), step_(step) {
  if (!(step_ > 0.0)) throw PlanningConfigError("motion validator: step must be > 0");
  if (!(max_climb_angle > 0.0 && max_climb_angle <= 90.0)) {
    throw PlanningConfigError("motion validator: max_climb_angle must be in (0, 90] deg");
  }
  max_climb_slope_ = max_climb_angle >= 90.0 ? std::numeric_limits<double>::infinity()
                                             : std::tan(max_climb_angle * M_PI / 180.0);
}

void MapMotionValidator::limitClimb(const ob::State* from, ob::State* to) const {
  if (std::isinf(max_climb_slope_)) return;
  const Eigen::Vector3d start = statePosition(from);
  auto* values = to->as<ob::RealVectorStateSpace::StateType>()->values;
  const double horizontal = std::hypot(values[0] - start.x(), values[1] - start.y());
  values[2] = std::max(values[2], start.z() - max_climb_slope_ * horizontal);
}

bool MapMotionValidator::withinClimbAngle(const ob::State* from, const ob::State* to) const {
  if (std::isinf(max_climb_slope_)) return true;
  const Eigen::Vector3d step = statePosition(to) - statePosition(from);
  return -step.z() <= max_climb_slope_ * step.head<2>().norm() + 1e-9;
}

bool MapMotionValidator::checkMotion(const ob::State* from, const ob::State* to) const {
  std::pair<ob::State*, double> unused(nullptr, 0.0);
  return checkMotion(from, to, unused);
}

bool MapMotionValidator::checkMotion(const ob::State* from, const ob::State* to,
                                     std::pair<ob::State*, double>& last_valid) const {
  // The end state is always checked. A start state that is valid is trusted (OMPL convention).
  // One that is not (the vehicle found itself too close to a wall just mapped) may only be left
  // by an escape: clearance never decreasing until the motion is valid again, then valid to
  // the end. Without it a vehicle inside the margin could never plan its way out.
  const ob::StateValidityChecker& checker = *si_->getStateValidityChecker();
  bool escaping = !si_->isValid(from);
  if (!escaping && !withinClimbAngle(from, to)) {
    ++invalid_;
    last_valid.second = 0.0;
    if (last_valid.first != nullptr) si_->copyState(last_valid.first, from);
    return false;
  }
  double previous_clearance = escaping ? checker.clearance(from) : 0.0;
  const double length = si_->distance(from, to);
  const int segments = std::max(1, static_cast<int>(std::ceil(length / step_)));
  ob::State* probe = si_->allocState();
  bool valid = true;
  int i = 1;
  for (; i <= segments; ++i) {
    si_->getStateSpace()->interpolate(from, to, static_cast<double>(i) / segments, probe);
    if (si_->isValid(probe)) {
      escaping = false;
      continue;
    }
    const double clearance = escaping ? checker.clearance(probe) : 0.0;
    if (!escaping || clearance < previous_clearance || i == segments) {
      valid = false;
      break;
    }
    previous_clearance = clearance;
  }
  if (valid) {
    ++valid_;
  } else {
    ++invalid_;
    last_valid.second = static_cast<double>(i - 1) / segments;
    if (last_valid.first != nullptr) {
      si_->getStateSpace()->interpolate(from, to, last_valid.second, last_valid.first);
    }
  }
  si_->freeState(probe);
  return valid;
}

ob::SpaceInformationPtr makeSpaceInformation(const PlanningSpaceOptions& space,
                                             std::shared_ptr<const DistanceField> field,
                                             const ClearanceOptions& clearance) {
  space.check();
  clearance.check();
  if (!field) throw PlanningConfigError("space information: null distance field");
  auto state_space = std::make_shared<ob::RealVectorStateSpace>(3);
  ob::RealVectorBounds bounds(3);
  for (int axis = 0; axis < 3; ++axis) {
    bounds.setLow(axis, space.min_corner[axis]);
    bounds.setHigh(axis, space.max_corner[axis]);
  }
  if (space.fixed_depth) {  // zero-width z interval: sampling and steering keep the depth
    bounds.setLow(2, *space.fixed_depth);
    bounds.setHigh(2, *space.fixed_depth);
  }
  state_space->setBounds(bounds);
  auto si = std::make_shared<ob::SpaceInformation>(state_space);
  const double half_resolution = 0.5 * field->resolution();
  const double step = clearance.motion_check_step > 0.0
                          ? std::min(clearance.motion_check_step, half_resolution)
                          : half_resolution;
  // Also for OMPL code that bypasses the motion validator (e.g. path simplification).
  state_space->setLongestValidSegmentFraction(
      std::min(1.0, step / std::max(step, state_space->getMaximumExtent())));
  si->setStateValidityChecker(std::make_shared<MapValidityChecker>(si, field, clearance));
  si->setMotionValidator(std::make_shared<MapMotionValidator>(si, step, clearance.max_climb_angle));
  si->setup();
  return si;
}

}  // namespace auv::planning
