// Shared by the planning benchmarks: the scenario's queries (read with yaml-cpp, nothing of the
// simulator is linked), a world's known map as the planner sees it, the planner settings of the
// `planning` component, planners by name, statistics and report helpers.
#pragma once

#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <octomap/OcTree.h>
#include <ompl/base/OptimizationObjective.h>
#include <ompl/base/Planner.h>
#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/SpaceInformation.h>
#include <Eigen/Core>

#include "auv/planning/distance_field.h"
#include "auv/planning/map_validity.h"
#include "auv/planning/visibility_cost.h"

namespace auv::planning::bench {

/// One start-to-goal query of a scenario.
struct BenchQuery {
  std::string name;
  Eigen::Vector3d start = Eigen::Vector3d::Zero();  ///< m NED
  Eigen::Vector3d goal = Eigen::Vector3d::Zero();   ///< m NED
  double tolerance = 1.5;                           ///< m, ε_goal
};

struct BenchScenario {
  std::string name;
  std::string file;
  double seabed_depth = 20.0;  ///< m
  /// The first query starts at vehicle.start, every later one where the previous one ended.
  std::vector<BenchQuery> queries;
};

/// Reads name, world.seabed_depth, vehicle.start.position and queries[] (goal, tolerance,
/// name); other keys are ignored. Throws std::runtime_error naming the file and the field.
BenchScenario readScenario(const std::string& path);

/// What the planner is run with. Defaults: the `planning` component's (PlanningComponent::
/// Options: range, goal_bias, narrow_passage_bias, rewire_factor, clearance, visibility_weight,
/// max_distance) and the mission handler's Eq. (1) defaults d_e = 1 m, Δd_a = 1 m.
struct PlannerSettings {
  double range = 0.0;
  double goal_bias = 0.0;
  double narrow_passage_bias = 0.0;  ///< OnlineRRTstar only
  double rewire_factor = 0.0;
  ClearanceOptions clearance;
  double visibility_weight = 0.0;
  double max_distance = 0.0;  ///< m, distance field clamp
  VisibilityCostOptions cost;
  /// true: plan in the horizontal plane at the query's start depth (the paper's 2-D setup and
  /// what `auv sim mission` asks for); false: 3-D between the surface and the seabed.
  bool fixed_depth = true;

  static PlannerSettings componentDefaults();
  std::string describe() const;
};

/// A world's static, fully known map (`auv sim octomap`) and its distance field over the map's
/// box.
struct WorldMap {
  std::unique_ptr<octomap::OcTree> tree;
  std::shared_ptr<OctomapDistanceField> field;
  Eigen::Vector3d min_corner = Eigen::Vector3d::Zero();  ///< m, the known box
  Eigen::Vector3d max_corner = Eigen::Vector3d::Zero();
  double build_seconds = 0.0;  ///< reading the map and building the field
};

/// Throws std::runtime_error when the file is not a readable .bt map.
WorldMap loadWorldMap(const std::string& bt_path, double max_distance);

/// One query's planning problem: space (bounds = the map box horizontally, the surface to the
/// seabed vertically, or the fixed depth), validity, the visibility objective and the states.
struct QueryProblem {
  ompl::base::SpaceInformationPtr si;
  ompl::base::OptimizationObjectivePtr objective;
  Eigen::Vector3d start = Eigen::Vector3d::Zero();  ///< as planned (on the fixed depth)
  Eigen::Vector3d goal = Eigen::Vector3d::Zero();
  double tolerance = 1.5;
  std::optional<double> fixed_depth;

  /// A fresh problem definition (start, goal within tolerance, the shared objective).
  ompl::base::ProblemDefinitionPtr makeProblemDefinition() const;
  /// Cost of `states` followed by the straight remainder to the goal point, so every planner's
  /// path is measured to the same point (solutions end anywhere within the tolerance).
  double costToGoal(const std::vector<const ompl::base::State*>& states) const;
  void setPosition(ompl::base::State* state, const Eigen::Vector3d& position) const;
};

QueryProblem makeQueryProblem(const WorldMap& map, const BenchQuery& query,
                              const PlannerSettings& settings, double seabed_depth);

/// "OnlineRRTstar", "RRTstar", "InformedRRTstar" or "BITstar", configured like the component
/// (range, goal bias, rewire factor where the planner has them). Not set up.
ompl::base::PlannerPtr makePlanner(const std::string& name, const QueryProblem& problem,
                                   const PlannerSettings& settings);
const std::vector<std::string>& plannerNames();

/// Linear-interpolation percentile (q in [0, 1]) of the values; NaN when empty. Infinite values
/// sort last (failed runs count as "slower than anything").
double percentile(std::vector<double> values, double q);

using Clock = std::chrono::steady_clock;
inline double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// "<cpus> CPUs, load average a b c" (the machine is shared: figures move with the load).
std::string machineNote();
/// YYYYmmdd_HHMMSS, local time.
std::string timestamp();
/// Number with `digits` decimals, "—" for NaN, "> budget" style text for infinity.
std::string formatNumber(double value, int digits, const std::string& infinite = "∞");

}  // namespace auv::planning::bench
