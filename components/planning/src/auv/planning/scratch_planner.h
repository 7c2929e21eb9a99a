#pragma once
// The online baselines of the mission campaign (issue 19): the same query and waypoint protocol
// as OnlineRRTstar, but a tree planned from scratch from the current root whenever the map
// changes or a waypoint is handed out (the root moved). No tree is ever reused; what is carried
// over is the plan being followed: the rest of the path after the waypoint handed out, kept
// while it stays valid and used when the fresh tree has nothing cheaper yet (a planner that
// throws away a valid plan it is executing would be a strawman).
//
// Two kinds of fresh tree: OMPL's own RRTstar (replanning: scratch, the textbook baseline) and
// the repair planner's OnlineRRTstar restarted each time (replanning: restart). The second
// differs from tree repair in nothing but the reuse — same sampling, same climb-limited
// steering — so the campaign can tell what the repair itself buys from what the steering does.

#include <cstdint>
#include <memory>
#include <vector>

#include "auv/planning/waypoint_planner.h"

namespace auv::planning {

class FreshTree;

class ScratchPlanner : public WaypointPlanner {
 public:
  /// `pdef` gives the goal (a GoalState at the goal tolerance) and the objective; each tree
  /// gets a problem definition of its own, rooted where that tree starts. `mode` is SCRATCH
  /// (OMPL's RRTstar) or RESTART (OnlineRRTstar); throws PlanningConfigError for REPAIR.
  ScratchPlanner(const ompl::base::SpaceInformationPtr& si,
                 const ompl::base::ProblemDefinitionPtr& pdef, const TreeSettings& settings,
                 Replanning mode);
  ~ScratchPlanner() override;
  ScratchPlanner(const ScratchPlanner&) = delete;
  ScratchPlanner& operator=(const ScratchPlanner&) = delete;

  ompl::base::PlannerStatus solve(const ompl::base::PlannerTerminationCondition& ptc) override;
  const ompl::base::State* rootState() const override { return root_; }
  std::size_t treeSize() const override;
  bool hasSolution() const override;
  /// Hands out the next state of bestPath(), keeps the rest as the plan followed and starts a
  /// new tree from the new root.
  bool popWaypoint(ompl::base::State* waypoint) override;
  /// Every map change starts a new tree from the root; the plan followed is dropped if a state
  /// or segment of it is no longer valid.
  UpdateResult updateTree(const ompl::base::State* vehicle_state) override;
  /// The same when `changed` is not empty; an empty change keeps the tree.
  UpdateResult updateTree(const ompl::base::State* vehicle_state,
                          const Eigen::AlignedBox3d& changed, double influence) override;
  void reset(const ompl::base::State* root_state) override;
  uint64_t iterations() const override;
  /// The cheaper (on the current map) of the fresh tree's best path and the plan followed.
  std::vector<const ompl::base::State*> bestPath() const override;
  ompl::base::Cost bestCost() const override;
  void snapshot(TreeSnapshot& tree) const override;
  const ompl::base::SpaceInformationPtr& spaceInformation() const override { return si_; }

  /// Trees started since the last reset() (the first one included).
  uint64_t trees() const { return trees_; }
  /// Sampling iterations of the current tree alone.
  uint64_t treeIterations() const;
  /// The rest of the plan followed (root excluded; empty: none).
  std::size_t plannedStates() const { return plan_.size(); }

 private:
  /// Drops the tree and starts a new one at root_.
  void restart();
  /// The fresh tree's path from root_ (empty without a solution).
  std::vector<const ompl::base::State*> treePath() const;
  /// root_ followed by plan_ (empty when plan_ is).
  std::vector<const ompl::base::State*> planPath() const;
  ompl::base::Cost pathCost(const std::vector<const ompl::base::State*>& path) const;
  bool rootInGoal() const;
  void freePlan();

  ompl::base::SpaceInformationPtr si_;
  ompl::base::ProblemDefinitionPtr pdef_;
  TreeSettings settings_;
  Replanning mode_;
  ompl::base::State* root_ = nullptr;
  std::vector<ompl::base::State*> plan_;  // after root_, up to the goal
  std::unique_ptr<FreshTree> tree_;
  uint64_t trees_ = 0;
  uint64_t earlier_iterations_ = 0;  // of the trees dropped since reset()
};

}  // namespace auv::planning
