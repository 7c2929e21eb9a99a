// Collision checking against the current map: clearance from the distance field, unknown
// space free (docs/paper.md §2.2.2). Checks are lazy in the paper's sense: a state or motion is
// judged on the map of the moment; OnlineRRTstar::updateTree re-checks the tree when the map
// grows.
#pragma once

#include <memory>
#include <optional>

#include <ompl/base/MotionValidator.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/StateValidityChecker.h>

#include "auv/config/option_table.h"
#include "auv/planning/distance_field.h"

namespace auv::planning {

struct ClearanceOptions {
  /// m, radius of the sphere enclosing the hull (Sparus II: 1.6 m long).
  double hull_radius = 0.8;
  /// m, extra distance kept on top of the hull radius (navigation drift between visits, map
  /// quantisation). Small enough that the narrowest canyon passage (4.2 m) stays open.
  double safety_margin = 0.4;
  /// deg, steepest climb of a motion (rising; dives are not limited). Keep it below the
  /// forward sonar's upper half-aperture: unknown space is free until seen and nothing looks
  /// up but the sonar's fan, so a steeper climb rises into water nobody has looked at (an
  /// arch's underside). Below, the fan's lower half, the DVL's beams and the controller's
  /// MIN_ALTITUDE manoeuvre watch a dive. 90 = no limit. Escapes from an invalid state are
  /// exempt.
  double max_climb_angle = 20.0;
  /// m, motion check step; <= 0 means half the map resolution. Never above half of it.
  double motion_check_step = 0.0;
  /// m, water kept between the clearance sphere (hull_radius + safety_margin) and known
  /// seabed directly below: a state with a known occupied cell less than min_altitude +
  /// clearance() below it in its column is invalid; 0 = the sphere only. Set per query
  /// (PlannerQuery.min_altitude), not a parameter.
  double min_altitude = 0.0;

  /// hull_radius, safety_margin and max_climb_angle with meaning, unit and range (the planning
  /// component's parameters of those names); motion_check_step is not a parameter.
  static const config::OptionTable<ClearanceOptions>& table();
  /// Throws PlanningConfigError naming the field.
  void check() const;
  double clearance() const { return hull_radius + safety_margin; }
};

/// Valid = inside the space bounds, at least clearance() from the nearest occupied cell (a
/// sphere: rock above, below and beside counts alike) and, with min_altitude > 0, no known
/// occupied cell within min_altitude + clearance() directly below (docs/paper.md §2.2.2 in 3-D).
class MapValidityChecker : public ompl::base::StateValidityChecker {
 public:
  MapValidityChecker(const ompl::base::SpaceInformationPtr& si,
                     std::shared_ptr<const DistanceField> field, const ClearanceOptions& options);

  bool isValid(const ompl::base::State* state) const override;
  /// Distance to the nearest occupied cell minus the required clearance, or the altitude over
  /// known seabed minus min_altitude + clearance when that is smaller (< 0: invalid).
  double clearance(const ompl::base::State* state) const override;

 private:
  /// The altitude term of clearance(): +infinity without known seabed within reach.
  double altitudeMargin(const Eigen::Vector3d& position, double distance) const;

  std::shared_ptr<const DistanceField> field_;
  ClearanceOptions options_;
};

/// Checks straight segments at a fixed metric step (<= half the map resolution), independent
/// of OMPL's longest_valid_segment_fraction, so thin obstacles are never stepped over; a
/// segment climbing more steeply than max_climb_angle (deg) is invalid unless it leaves an
/// invalid state.
class MapMotionValidator : public ompl::base::MotionValidator {
 public:
  MapMotionValidator(const ompl::base::SpaceInformationPtr& si, double step,
                     double max_climb_angle = 90.0);

  bool checkMotion(const ompl::base::State* from, const ompl::base::State* to) const override;
  bool checkMotion(const ompl::base::State* from, const ompl::base::State* to,
                   std::pair<ompl::base::State*, double>& last_valid) const override;
  double step() const { return step_; }
  /// Lowers `to` (raises its depth) so that the motion from `from` climbs no more steeply
  /// than the limit: a planner's steering, so that a sample above a node still grows the tree
  /// by a climb it may take instead of being thrown away.
  void limitClimb(const ompl::base::State* from, ompl::base::State* to) const;

 private:
  /// Whether the segment climbs no more steeply than the limit (z is depth: rising = z falls).
  bool withinClimbAngle(const ompl::base::State* from, const ompl::base::State* to) const;

  double step_;
  double max_climb_slope_;  // rise / horizontal distance; infinity = no limit
};

struct PlanningSpaceOptions {
  /// m, NED bounds of the planning volume.
  Eigen::Vector3d min_corner{-50.0, -50.0, 0.5};
  Eigen::Vector3d max_corner{50.0, 50.0, 30.0};
  /// m, when set, every state has this depth (2-D planning as the paper did with a
  /// horizontal profiler); it must lie within [min_corner.z, max_corner.z].
  std::optional<double> fixed_depth;

  void check() const;
};

/// A RealVectorStateSpace(3) (NED) with the bounds (z collapsed to fixed_depth if set), and a
/// SpaceInformation using MapValidityChecker + MapMotionValidator; it is set up.
ompl::base::SpaceInformationPtr makeSpaceInformation(const PlanningSpaceOptions& space,
                                                     std::shared_ptr<const DistanceField> field,
                                                     const ClearanceOptions& clearance);

}  // namespace auv::planning
