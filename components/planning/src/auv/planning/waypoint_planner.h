#pragma once
// What the planning session needs from a planner, so that the paper's tree repair
// (OnlineRRTstar) and the from-scratch baseline (ScratchPlanner) run behind the same query and
// waypoint protocol: a tree rooted where the vehicle will be, grown in slices, popped one
// waypoint at a time and checked again when the map changes.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <ompl/base/Cost.h>
#include <ompl/base/PlannerStatus.h>
#include <ompl/base/PlannerTerminationCondition.h>
#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/SpaceInformation.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace auv::planning {

/// What updateTree() found.
struct UpdateResult {
  bool root_in_collision = false;        ///< the root (the active waypoint) is not valid
  bool vehicle_to_root_blocked = false;  ///< the segment vehicle -> root is not valid
  std::size_t removed_nodes = 0;         ///< nodes discarded with their colliding subtrees
  /// The caller must cancel the active waypoint and reset() from the vehicle's position.
  bool needsRestart() const { return root_in_collision || vehicle_to_root_blocked; }
};

/// The active tree as the viewers see it, depth-first from the root (a parent always comes
/// before its children).
struct TreeSnapshot {
  std::vector<Eigen::Vector3d> nodes;
  std::vector<int32_t> parents;  ///< -1 for the root
  std::vector<double> costs;     ///< cost-to-come
  int32_t root_index = -1;
  int32_t best_solution_index = -1;
  std::vector<int32_t> solution_indices;  ///< nodes within the goal tolerance of the goal
  uint64_t iterations = 0;                ///< of the whole query, restarts included
};

class WaypointPlanner {
 public:
  virtual ~WaypointPlanner() = default;

  /// Grows the tree until `ptc` (anytime: later calls go on growing it).
  virtual ompl::base::PlannerStatus solve(const ompl::base::PlannerTerminationCondition& ptc) = 0;
  /// The root's state (where the vehicle heads for); nullptr before the first reset().
  virtual const ompl::base::State* rootState() const = 0;
  virtual std::size_t treeSize() const = 0;
  /// Whether a path from the root to the goal is known.
  virtual bool hasSolution() const = 0;
  /// Writes the state after the root on the best path to `waypoint`, which becomes the root.
  /// False (nothing changed) without a solution or when the root is the goal.
  virtual bool popWaypoint(ompl::base::State* waypoint) = 0;
  /// The map changed anywhere.
  virtual UpdateResult updateTree(const ompl::base::State* vehicle_state) = 0;
  /// The map changed only inside `changed`; edges farther than `influence` from it keep their
  /// validity and cost.
  virtual UpdateResult updateTree(const ompl::base::State* vehicle_state,
                                  const Eigen::AlignedBox3d& changed, double influence) = 0;
  /// Drops everything and restarts at `root_state` (keeps the goal).
  virtual void reset(const ompl::base::State* root_state) = 0;
  /// Sampling iterations since the last reset().
  virtual uint64_t iterations() const = 0;
  /// States from the root to the end of the best path (empty without a solution).
  virtual std::vector<const ompl::base::State*> bestPath() const = 0;
  /// Cost of bestPath(); infinite without a solution.
  virtual ompl::base::Cost bestCost() const = 0;
  /// Fills nodes, parents, costs, root_index and best_solution_index of `tree`.
  virtual void snapshot(TreeSnapshot& tree) const = 0;
  /// The space the tree lives in (its validity and motion checks).
  virtual const ompl::base::SpaceInformationPtr& spaceInformation() const = 0;
};

/// How the planner handles a map change (the planning component's `replanning`).
enum class Replanning {
  REPAIR,   ///< the paper's: one anytime tree, re-checked and pruned (OnlineRRTstar)
  SCRATCH,  ///< the baseline: OMPL's RRTstar planned anew from the root (ScratchPlanner)
  /// the baseline with the repair planner's own tree: OnlineRRTstar planned anew from the root
  /// (ScratchPlanner), i.e. tree repair without the reuse
  RESTART,
};

/// "repair", "scratch" or "restart"; throws PlanningConfigError otherwise.
Replanning replanningFromName(const std::string& name);

struct TreeSettings {
  double range = 2.0;  ///< m, δ
  double goal_bias = 0.05;
  double narrow_passage_bias = 0.1;
  double rewire_factor = 1.1;
  double goal_tolerance = 1.0;  ///< m
};

/// The planner of `mode` on `pdef` (start, goal and objective; `si` set up), rooted at `root`
/// even when `root` is inside the clearance (the motion validator lets the tree leave it).
std::shared_ptr<WaypointPlanner> makeWaypointPlanner(Replanning mode, const TreeSettings& settings,
                                                     const ompl::base::SpaceInformationPtr& si,
                                                     const ompl::base::ProblemDefinitionPtr& pdef,
                                                     const ompl::base::State* root);

}  // namespace auv::planning
