#include "auv/planning/scratch_planner.h"

#include <algorithm>
#include <utility>

#include <ompl/base/Goal.h>
#include <ompl/base/samplers/BridgeTestValidStateSampler.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/planners/rrt/RRTstar.h>
#include <ompl/util/Console.h>

#include "auv/planning/distance_field.h"
#include "auv/planning/online_rrt_star.h"

namespace auv::planning {

namespace ob = ompl::base;

namespace {

/// OMPL's RRTstar draws its random states from sampleUniform(): this one draws a share of them
/// with the bridge test, as OnlineRRTstar does with narrow_passage_bias, so both planners see
/// the same narrow passages.
class BridgeMixSampler : public ob::StateSampler {
 public:
  BridgeMixSampler(const ob::SpaceInformation* si, double bias, double spread)
      : ob::StateSampler(si->getStateSpace().get()),
        uniform_(si->allocStateSampler()),
        bridge_(si),
        bias_(bias) {
    bridge_.setStdDev(spread);
  }
  void sampleUniform(ob::State* state) override {
    // Where the bridge test finds no passage (nothing invalid nearby) it fails: uniform then.
    if (bias_ > 0.0 && rng_.uniform01() < bias_ && bridge_.sample(state)) return;
    uniform_->sampleUniform(state);
  }
  void sampleUniformNear(ob::State* state, const ob::State* near, double distance) override {
    uniform_->sampleUniformNear(state, near, distance);
  }
  void sampleGaussian(ob::State* state, const ob::State* mean, double stddev) override {
    uniform_->sampleGaussian(state, mean, stddev);
  }

 private:
  ob::StateSamplerPtr uniform_;
  ob::BridgeTestValidStateSampler bridge_;
  double bias_;
};

}  // namespace

/// One tree of the baseline, grown from the root until the next map change or waypoint.
class FreshTree {
 public:
  virtual ~FreshTree() = default;
  virtual ob::PlannerStatus solve(const ob::PlannerTerminationCondition& ptc) = 0;
  virtual std::size_t size() const = 0;
  virtual uint64_t iterations() const = 0;
  /// States from the root to the best goal node, each edge valid the way it is flown (empty
  /// without one).
  virtual std::vector<const ob::State*> path() const = 0;
  virtual void fill(TreeSnapshot& tree) const = 0;
};

namespace {

/// OMPL's RRTstar, unchanged, with access to what the session shows and needs: its tree, its
/// best goal motion, a root inside the clearance and the sampler.
class FreshRRTstar : public ompl::geometric::RRTstar {
 public:
  using RRTstar::RRTstar;

  /// After setup(): the root is added by hand, so the tree has it before the first solve()
  /// (as OnlineRRTstar's) and even when it is not valid (a vehicle that drifted close to a
  /// wall), which OMPL's start-state input would skip, leaving no tree; the motion validator
  /// lets the tree leave such a root by moving away from the wall.
  void plant(const ob::State* root, ob::StateSamplerPtr sampler) {
    sampler_ = std::move(sampler);  // solve() allocates its own only when none is set
    auto* motion = new Motion(si_);
    si_->copyState(motion->state, root);
    motion->cost = opt_->identityCost();
    nn_->add(motion);
    startMotions_.push_back(motion);
    // Use up the problem definition's copy of the root, so that solve() adds no second one.
    if (si_->isValid(root)) pis_.nextStart();
  }
  std::size_t size() const { return nn_ ? nn_->size() : 0; }
  /// States from the root to the best goal motion (empty without one).
  std::vector<const ob::State*> path() const {
    std::vector<const ob::State*> states;
    for (const Motion* m = bestGoalMotion_; m != nullptr; m = m->parent) states.push_back(m->state);
    std::reverse(states.begin(), states.end());
    return states;
  }
  void fill(TreeSnapshot& tree) const {
    std::vector<std::pair<const Motion*, int32_t>> stack;
    for (const Motion* start : startMotions_) stack.emplace_back(start, -1);
    while (!stack.empty()) {
      const auto [motion, parent] = stack.back();
      stack.pop_back();
      const auto index = static_cast<int32_t>(tree.nodes.size());
      const auto* values = motion->state->as<ob::RealVectorStateSpace::StateType>()->values;
      tree.nodes.emplace_back(values[0], values[1], values[2]);
      tree.parents.push_back(parent);
      tree.costs.push_back(motion->cost.value());
      if (parent < 0 && tree.root_index < 0) tree.root_index = index;
      if (motion == bestGoalMotion_) tree.best_solution_index = index;
      for (const Motion* child : motion->children) stack.emplace_back(child, index);
    }
  }
};

/// replanning: scratch.
class OmplTree : public FreshTree {
 public:
  OmplTree(const ob::SpaceInformationPtr& si, const ob::ProblemDefinitionPtr& pdef,
           const TreeSettings& settings, const ob::State* root)
      : rrt_(std::make_shared<FreshRRTstar>(si)) {
    rrt_->setRange(settings.range);
    rrt_->setGoalBias(settings.goal_bias);
    rrt_->setRewireFactor(settings.rewire_factor);
    // k-nearest (OMPL's default): its radius variant takes the measure of all three
    // dimensions, which is 0 in the fixed-depth plane and would switch rewiring off.
    rrt_->setKNearest(true);
    rrt_->setProblemDefinition(pdef);
    rrt_->setup();
    // RRTstar samples the goal itself (goal_bias); the bridge share of the rest makes the
    // narrow_passage_bias of all random states, as in OnlineRRTstar.
    const double bridge_share =
        settings.goal_bias < 1.0 ? settings.narrow_passage_bias / (1.0 - settings.goal_bias) : 0.0;
    rrt_->plant(root, std::make_shared<BridgeMixSampler>(si.get(), bridge_share, settings.range));
  }
  ob::PlannerStatus solve(const ob::PlannerTerminationCondition& ptc) override {
    return rrt_->solve(ptc);
  }
  std::size_t size() const override { return rrt_->size(); }
  uint64_t iterations() const override { return rrt_->numIterations(); }
  std::vector<const ob::State*> path() const override {
    std::vector<const ob::State*> states = rrt_->path();
    // RRTstar reuses a neighbour's validity check for the rewire in the other direction when
    // the cost is symmetric; the climb limit makes validity directional, so a rewired edge may
    // climb too steeply. Such a path is no solution. (OnlineRRTstar checks each edge the way it
    // is flown already.)
    const auto& si = rrt_->getSpaceInformation();
    for (std::size_t i = 1; i < states.size(); ++i) {
      if (!si->checkMotion(states[i - 1], states[i])) return {};
    }
    return states;
  }
  void fill(TreeSnapshot& tree) const override { rrt_->fill(tree); }

 private:
  std::shared_ptr<FreshRRTstar> rrt_;
};

/// replanning: restart.
class OnlineTree : public FreshTree {
 public:
  OnlineTree(const ob::SpaceInformationPtr& si, const ob::ProblemDefinitionPtr& pdef,
             const TreeSettings& settings, const ob::State* root)
      : rrt_(makeOnlineRRTstar(settings, si, pdef, root)) {}
  ob::PlannerStatus solve(const ob::PlannerTerminationCondition& ptc) override {
    return rrt_->solve(ptc);
  }
  std::size_t size() const override { return rrt_->treeSize(); }
  uint64_t iterations() const override { return rrt_->iterations(); }
  std::vector<const ob::State*> path() const override { return rrt_->bestPath(); }
  void fill(TreeSnapshot& tree) const override { rrt_->snapshot(tree); }

 private:
  std::shared_ptr<OnlineRRTstar> rrt_;
};

}  // namespace

ScratchPlanner::ScratchPlanner(const ob::SpaceInformationPtr& si,
                               const ob::ProblemDefinitionPtr& pdef, const TreeSettings& settings,
                               Replanning mode)
    : si_(si), pdef_(pdef), settings_(settings), mode_(mode) {
  if (mode == Replanning::REPAIR) {
    throw PlanningConfigError("ScratchPlanner: replanning must be scratch or restart, not repair");
  }
  // RRTstar informs twice per solve() call, i.e. twenty lines a second in planning slices.
  if (ompl::msg::getLogLevel() < ompl::msg::LOG_WARN) ompl::msg::setLogLevel(ompl::msg::LOG_WARN);
}

ScratchPlanner::~ScratchPlanner() {
  tree_.reset();
  freePlan();
  if (root_) si_->freeState(root_);
}

void ScratchPlanner::freePlan() {
  for (ob::State* state : plan_) si_->freeState(state);
  plan_.clear();
}

void ScratchPlanner::restart() {
  if (tree_) earlier_iterations_ += tree_->iterations();
  tree_.reset();
  auto pdef = std::make_shared<ob::ProblemDefinition>(si_);
  pdef->addStartState(root_);
  pdef->setGoal(pdef_->getGoal());
  pdef->setOptimizationObjective(pdef_->getOptimizationObjective());
  if (mode_ == Replanning::RESTART) {
    tree_ = std::make_unique<OnlineTree>(si_, pdef, settings_, root_);
  } else {
    tree_ = std::make_unique<OmplTree>(si_, pdef, settings_, root_);
  }
  ++trees_;
}

void ScratchPlanner::reset(const ob::State* root_state) {
  if (!root_) root_ = si_->allocState();
  si_->copyState(root_, root_state);
  freePlan();
  tree_.reset();
  earlier_iterations_ = 0;
  trees_ = 0;
  restart();
}

ob::PlannerStatus ScratchPlanner::solve(const ob::PlannerTerminationCondition& ptc) {
  if (!tree_) return ob::PlannerStatus::INVALID_START;
  return tree_->solve(ptc);
}

std::size_t ScratchPlanner::treeSize() const { return tree_ ? tree_->size() : 0; }

uint64_t ScratchPlanner::treeIterations() const { return tree_ ? tree_->iterations() : 0; }

uint64_t ScratchPlanner::iterations() const { return earlier_iterations_ + treeIterations(); }

bool ScratchPlanner::rootInGoal() const {
  return root_ != nullptr && pdef_->getGoal()->isSatisfied(root_);
}

bool ScratchPlanner::hasSolution() const {
  return rootInGoal() || !plan_.empty() || !treePath().empty();
}

std::vector<const ob::State*> ScratchPlanner::treePath() const {
  return tree_ ? tree_->path() : std::vector<const ob::State*>{};
}

std::vector<const ob::State*> ScratchPlanner::planPath() const {
  if (plan_.empty()) return {};
  std::vector<const ob::State*> path{root_};
  path.insert(path.end(), plan_.begin(), plan_.end());
  return path;
}

ob::Cost ScratchPlanner::pathCost(const std::vector<const ob::State*>& path) const {
  const auto& objective = pdef_->getOptimizationObjective();
  if (path.empty()) return objective->infiniteCost();
  ob::Cost cost = objective->identityCost();
  for (std::size_t i = 1; i < path.size(); ++i) {
    cost = objective->combineCosts(cost, objective->motionCost(path[i - 1], path[i]));
  }
  return cost;
}

std::vector<const ob::State*> ScratchPlanner::bestPath() const {
  if (rootInGoal()) return {root_};
  std::vector<const ob::State*> fresh = treePath();
  std::vector<const ob::State*> plan = planPath();
  if (fresh.empty()) return plan;
  if (plan.empty()) return fresh;
  // Both on the current map: a fresh tree only replaces the plan followed when it is cheaper.
  const auto& objective = pdef_->getOptimizationObjective();
  return objective->isCostBetterThan(pathCost(fresh), pathCost(plan)) ? fresh : plan;
}

ob::Cost ScratchPlanner::bestCost() const { return pathCost(bestPath()); }

bool ScratchPlanner::popWaypoint(ob::State* waypoint) {
  const std::vector<const ob::State*> path = bestPath();
  if (path.size() < 2) return false;
  si_->copyState(waypoint, path[1]);
  // Cloned before the tree (which may own them) goes.
  std::vector<ob::State*> rest;
  for (std::size_t i = 2; i < path.size(); ++i) rest.push_back(si_->cloneState(path[i]));
  si_->copyState(root_, path[1]);
  freePlan();
  plan_ = std::move(rest);
  restart();  // the old tree is rooted where the vehicle no longer is
  return true;
}

UpdateResult ScratchPlanner::updateTree(const ob::State* vehicle_state) {
  return updateTree(
      vehicle_state,
      Eigen::AlignedBox3d(Eigen::Vector3d::Constant(-1e300), Eigen::Vector3d::Constant(1e300)),
      0.0);
}

UpdateResult ScratchPlanner::updateTree(const ob::State* vehicle_state,
                                        const Eigen::AlignedBox3d& changed, double /*influence*/) {
  UpdateResult result;
  if (root_ == nullptr) return result;
  result.root_in_collision = !si_->isValid(root_);
  result.vehicle_to_root_blocked =
      vehicle_state != nullptr && !si_->checkMotion(vehicle_state, root_);
  if (changed.isEmpty()) return result;  // nothing changed: the tree goes on growing
  const ob::State* previous = root_;
  for (const ob::State* state : plan_) {
    if (!si_->isValid(state) || !si_->checkMotion(previous, state)) {
      freePlan();
      break;
    }
    previous = state;
  }
  result.removed_nodes = treeSize();
  restart();
  return result;
}

void ScratchPlanner::snapshot(TreeSnapshot& tree) const {
  if (tree_) tree_->fill(tree);
}

}  // namespace auv::planning
