// The paper's modified RRT* (docs/paper.md §2.2.1, Algorithms 1 and 2): one tree grown anytime,
// pruned to the next waypoint when the mission handler asks for it, and repaired by
// updateTree() when the map changes (delayed collision checking).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <vector>

#include <ompl/base/OptimizationObjective.h>
#include <ompl/base/Planner.h>
#include <ompl/base/samplers/BridgeTestValidStateSampler.h>
#include <ompl/datastructures/NearestNeighbors.h>
#include <ompl/util/RandomNumbers.h>
#include <Eigen/Geometry>

#include "auv/planning/waypoint_planner.h"

namespace auv::planning {

class MapMotionValidator;

/// Parameters (declareParam): range (δ, m), goal_bias, goal_tolerance (ε_goal, m),
/// rewire_factor, narrow_passage_bias (share of the random states drawn by OMPL's bridge test,
/// which finds the midpoints of narrow passages that uniform sampling rarely hits; 0 = the
/// paper's uniform sampling) and narrow_passage_spread (m, the bridge's standard deviation;
/// 0 = δ). Works with OMPL's SimpleSetup and Benchmark: solve() grows the tree from
/// the problem's start (or the current root), keeps growing across calls (anytime) until
/// clear() or reset(), and reports the best solution so far.
class OnlineRRTstar : public ompl::base::Planner, public WaypointPlanner {
 public:
  /// A tree node. `cost` is the cost-to-come from the root; `incoming_cost` the edge cost.
  struct Node {
    ompl::base::State* state = nullptr;
    Node* parent = nullptr;
    std::vector<Node*> children;
    ompl::base::Cost cost;
    ompl::base::Cost incoming_cost;
  };

  explicit OnlineRRTstar(const ompl::base::SpaceInformationPtr& si);
  ~OnlineRRTstar() override;

  void setup() override;
  void clear() override;
  /// Algorithm 1 without the waypoint step: grows the tree until `ptc`, adding nodes within
  /// ε_goal of the goal to the solution list; posts the best path to the problem definition.
  ompl::base::PlannerStatus solve(const ompl::base::PlannerTerminationCondition& ptc) override;
  void getPlannerData(ompl::base::PlannerData& data) const override;

  /// Algorithm 1 lines 10-14: if a solution exists, writes the state after the root on the
  /// best solution to `waypoint` and prunes the tree so it becomes the root (the other
  /// subtrees are freed). False (tree untouched) when there is no solution or the root
  /// itself is the best solution.
  bool popWaypoint(ompl::base::State* waypoint) override;
  /// DFS re-check of every node and edge on the current map; colliding subtrees are freed.
  UpdateResult updateTree(const ompl::base::State* vehicle_state) override;
  /// The same, when the map changed only inside `changed` (RealVector states): edges whose
  /// bounding box stays `influence` metres away from it (the clearance, or how far the
  /// objective looks if farther) keep their validity and cost without a check.
  UpdateResult updateTree(const ompl::base::State* vehicle_state,
                          const Eigen::AlignedBox3d& changed, double influence) override;
  /// Drops the tree and restarts it with `root_state` as root (keeps the goal).
  void reset(const ompl::base::State* root_state) override;

  /// Best solution node (lowest cost-to-come + cost to the goal), or nullptr.
  const Node* bestSolution() const;
  /// Cost of bestSolution() up to the goal; infinite cost when there is none.
  ompl::base::Cost bestCost() const override;
  /// States from the root to the best solution node (empty when there is none).
  std::vector<const ompl::base::State*> bestPath() const override;
  const Node* root() const { return root_; }
  const ompl::base::State* rootState() const override { return root_ ? root_->state : nullptr; }
  std::size_t treeSize() const override { return nn_ ? nn_->size() : 0; }
  bool hasSolution() const override { return !solutions_.empty(); }
  /// Sampling iterations since the last clear() or reset().
  uint64_t iterations() const override { return iterations_; }
  void snapshot(TreeSnapshot& tree) const override;
  const ompl::base::SpaceInformationPtr& spaceInformation() const override { return si_; }
  /// Checks parent/child links, costs and the nearest-neighbour structure; true if consistent.
  bool checkConsistency() const;

  void setRange(double range) { range_ = range; }
  double getRange() const { return range_; }
  void setGoalBias(double goal_bias) { goal_bias_ = goal_bias; }
  double getGoalBias() const { return goal_bias_; }
  void setGoalTolerance(double tolerance) { goal_tolerance_ = tolerance; }
  double getGoalTolerance() const { return goal_tolerance_; }
  void setRewireFactor(double factor) { rewire_factor_ = factor; }
  double getRewireFactor() const { return rewire_factor_; }
  void setNarrowPassageBias(double bias) { narrow_passage_bias_ = bias; }
  double getNarrowPassageBias() const { return narrow_passage_bias_; }
  void setNarrowPassageSpread(double spread) { narrow_passage_spread_ = spread; }
  double getNarrowPassageSpread() const { return narrow_passage_spread_; }

 private:
  /// The random state of one iteration: the goal or a state near it (goal_bias), a bridge-test
  /// state (narrow_passage_bias, when the bridge test finds one) or a uniform state.
  void sampleRandomState(ompl::base::State* random_state);
  /// Algorithm 2: nearest, steer by δ, check, choose parent, add, rewire. Null if trapped.
  Node* extend(const ompl::base::State* random_state);
  Node* addRoot(const ompl::base::State* state);
  bool initializeGoal();
  double nearRadius() const;
  ompl::base::Cost costToGoal(const Node* node) const;
  bool reachesGoal(const Node* node) const;
  void propagateCost(Node* node);
  void detachFromParent(Node* node);
  void freeSubtree(Node* node);
  /// updateTree() over the edges `affected` says may have changed (all when it is empty).
  UpdateResult recheckTree(const ompl::base::State* vehicle_state,
                           const std::function<bool(const Node*, const Node*)>& affected);
  /// Detaches `subtree_root` from its parent and appends its nodes to `removed`.
  void detachSubtree(Node* subtree_root, std::vector<Node*>& removed);
  /// Drops the detached `removed` nodes from the nearest-neighbour structure and the solution
  /// list (by re-indexing the tree), then frees them.
  void discard(const std::vector<Node*>& removed);
  /// Rebuilds the nearest-neighbour structure and the solution list from the tree.
  void reindex();
  void freeTree();
  void postSolution(bool approximate);

  std::shared_ptr<ompl::NearestNeighbors<Node*>> nn_;
  ompl::base::StateSamplerPtr sampler_;
  std::shared_ptr<ompl::base::BridgeTestValidStateSampler> bridge_sampler_;
  ompl::RNG rng_;
  ompl::base::OptimizationObjectivePtr objective_;
  /// The space's MapMotionValidator when it has one (climb-limited steering), set in setup().
  std::shared_ptr<const MapMotionValidator> climb_limit_;
  Node* root_ = nullptr;
  std::vector<Node*> solutions_;
  ompl::base::State* goal_state_ = nullptr;

  double range_ = 0.0;  ///< 0: 0.2 × the space's maximum extent (OMPL default), set in setup()
  double goal_bias_ = 0.05;
  double goal_tolerance_ = 1.0;
  double rewire_factor_ = 1.1;
  double narrow_passage_bias_ = 0.0;
  double narrow_passage_spread_ = 0.0;  ///< m; 0: range_
  /// bestCost() for the benchmark's progress thread (read without touching the tree).
  std::atomic<double> published_best_cost_{std::numeric_limits<double>::infinity()};
  double rrt_star_gamma_ = 0.0;  ///< RRT* radius constant, from the free-space measure
  double effective_dimension_ = 3.0;
  uint64_t iterations_ = 0;
};

/// OnlineRRTstar with `settings` on `pdef` (start, goal and objective; `si` set up), set up and
/// rooted at `root` even when `root` is inside the clearance: OMPL's start-state input skips
/// invalid starts and would leave no tree, while the motion validator lets the tree leave such
/// a root by moving away from the wall (a vehicle that drifted close to it).
std::shared_ptr<OnlineRRTstar> makeOnlineRRTstar(const TreeSettings& settings,
                                                 const ompl::base::SpaceInformationPtr& si,
                                                 const ompl::base::ProblemDefinitionPtr& pdef,
                                                 const ompl::base::State* root);

}  // namespace auv::planning
