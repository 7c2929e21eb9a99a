#include "auv/planning/online_rrt_star.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_set>

#include <ompl/base/goals/GoalSampleableRegion.h>
#include <ompl/base/objectives/PathLengthOptimizationObjective.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/tools/config/SelfConfig.h>
#include <ompl/util/GeometricEquations.h>

#include "auv/planning/map_validity.h"

namespace auv::planning {
namespace ob = ompl::base;

namespace {
/// Relative tolerance when comparing recomputed costs in checkConsistency().
constexpr double kCostTolerance = 1e-6;
/// Tree sizes between refreshes of the cost the progress thread reads.
constexpr std::size_t kPublishCostEvery = 64;

}  // namespace

OnlineRRTstar::OnlineRRTstar(const ob::SpaceInformationPtr& si) : ob::Planner(si, "OnlineRRTstar") {
  specs_.approximateSolutions = false;
  specs_.optimizingPaths = true;
  specs_.canReportIntermediateSolutions = false;
  declareParam<double>("range", this, &OnlineRRTstar::setRange, &OnlineRRTstar::getRange,
                       "0.:1.:10000.");
  declareParam<double>("goal_bias", this, &OnlineRRTstar::setGoalBias, &OnlineRRTstar::getGoalBias,
                       "0.:.05:1.");
  declareParam<double>("goal_tolerance", this, &OnlineRRTstar::setGoalTolerance,
                       &OnlineRRTstar::getGoalTolerance, "0.:.1:100.");
  declareParam<double>("rewire_factor", this, &OnlineRRTstar::setRewireFactor,
                       &OnlineRRTstar::getRewireFactor, "1.0:0.01:2.0");
  declareParam<double>("narrow_passage_bias", this, &OnlineRRTstar::setNarrowPassageBias,
                       &OnlineRRTstar::getNarrowPassageBias, "0.:.05:1.");
  declareParam<double>("narrow_passage_spread", this, &OnlineRRTstar::setNarrowPassageSpread,
                       &OnlineRRTstar::getNarrowPassageSpread, "0.:.1:100.");
  addPlannerProgressProperty("best cost REAL",
                             [this] { return std::to_string(published_best_cost_.load()); });
}

OnlineRRTstar::~OnlineRRTstar() {
  freeTree();
  if (goal_state_) si_->freeState(goal_state_);
}

void OnlineRRTstar::setup() {
  ob::Planner::setup();
  ompl::tools::SelfConfig self_config(si_, getName());
  self_config.configurePlannerRange(range_);
  climb_limit_ = std::dynamic_pointer_cast<const MapMotionValidator>(si_->getMotionValidator());
  if (!nn_) nn_.reset(ompl::tools::SelfConfig::getDefaultNearestNeighbors<Node*>(this));
  nn_->setDistanceFunction(
      [this](const Node* a, const Node* b) { return si_->distance(a->state, b->state); });
  if (pdef_) {
    if (!pdef_->hasOptimizationObjective()) {
      pdef_->setOptimizationObjective(std::make_shared<ob::PathLengthOptimizationObjective>(si_));
    }
    objective_ = pdef_->getOptimizationObjective();
  }
  // Free-space measure of the sampled dimensions (a fixed depth collapses z).
  double measure = si_->getSpaceMeasure();
  effective_dimension_ = si_->getStateDimension();
  if (auto* real = dynamic_cast<ob::RealVectorStateSpace*>(si_->getStateSpace().get())) {
    measure = 1.0;
    effective_dimension_ = 0.0;
    for (double extent : real->getBounds().getDifference()) {
      if (extent > 0.0) {
        measure *= extent;
        effective_dimension_ += 1.0;
      }
    }
    effective_dimension_ = std::max(1.0, effective_dimension_);
  }
  const double d = effective_dimension_;
  rrt_star_gamma_ =
      std::pow(2.0 * (1.0 + 1.0 / d) * (measure / ompl::unitNBallMeasure(static_cast<unsigned>(d))),
               1.0 / d);
}

void OnlineRRTstar::clear() {
  ob::Planner::clear();
  freeTree();
  sampler_.reset();
  bridge_sampler_.reset();
  if (goal_state_) si_->freeState(goal_state_);
  goal_state_ = nullptr;
}

void OnlineRRTstar::freeTree() {
  if (root_) freeSubtree(root_);
  root_ = nullptr;
  iterations_ = 0;
  solutions_.clear();
  if (nn_) nn_->clear();
}

void OnlineRRTstar::freeSubtree(Node* node) {
  std::vector<Node*> stack{node};
  while (!stack.empty()) {
    Node* current = stack.back();
    stack.pop_back();
    stack.insert(stack.end(), current->children.begin(), current->children.end());
    si_->freeState(current->state);
    delete current;
  }
}

OnlineRRTstar::Node* OnlineRRTstar::addRoot(const ob::State* state) {
  root_ = new Node;
  root_->state = si_->cloneState(state);
  root_->cost = objective_->identityCost();
  root_->incoming_cost = objective_->identityCost();
  nn_->add(root_);
  if (goal_state_ && reachesGoal(root_)) solutions_.push_back(root_);
  return root_;
}

bool OnlineRRTstar::initializeGoal() {
  if (goal_state_) return true;
  auto* goal = dynamic_cast<ob::GoalSampleableRegion*>(pdef_->getGoal().get());
  if (goal == nullptr || !goal->canSample()) return false;
  goal_state_ = si_->allocState();
  goal->sampleGoal(goal_state_);
  return true;
}

ob::PlannerStatus OnlineRRTstar::solve(const ob::PlannerTerminationCondition& ptc) {
  checkValidity();
  if (!objective_) objective_ = pdef_->getOptimizationObjective();
  if (!initializeGoal()) return ob::PlannerStatus::INVALID_GOAL;
  if (root_ == nullptr) {
    const ob::State* start = pis_.nextStart();
    if (start == nullptr) return ob::PlannerStatus::INVALID_START;
    addRoot(start);
  }
  ob::State* random_state = si_->allocState();
  while (!ptc) {
    ++iterations_;
    sampleRandomState(random_state);
    Node* added = extend(random_state);
    if (added == nullptr) continue;
    const bool new_solution = reachesGoal(added);
    if (new_solution) solutions_.push_back(added);
    // Rewiring also improves existing solutions: refresh the published cost now and then.
    if (new_solution || (!solutions_.empty() && nn_->size() % kPublishCostEvery == 0)) {
      published_best_cost_ = bestCost().value();
    }
  }
  published_best_cost_ = bestCost().value();
  si_->freeState(random_state);
  if (solutions_.empty()) return ob::PlannerStatus::TIMEOUT;
  postSolution(false);
  return ob::PlannerStatus::EXACT_SOLUTION;
}

void OnlineRRTstar::sampleRandomState(ob::State* random_state) {
  if (!sampler_) sampler_ = si_->allocStateSampler();
  const double draw = rng_.uniform01();
  if (draw < goal_bias_) {
    // Half the goal draws are the goal itself (the straight pull), half a state near it within
    // the tolerance: the goal's nearest node is often the same one, and where the way from it
    // is blocked (below a ledge the goal sits on, beyond a climb the limit forbids) every exact
    // goal draw fails there again, while a spread one can enter the goal region from another
    // node and side.
    if (draw < 0.5 * goal_bias_) {
      si_->copyState(random_state, goal_state_);
    } else {
      sampler_->sampleUniformNear(random_state, goal_state_, goal_tolerance_);
    }
    return;
  }
  if (draw < goal_bias_ + narrow_passage_bias_) {
    if (!bridge_sampler_) {
      bridge_sampler_ = std::make_shared<ob::BridgeTestValidStateSampler>(si_.get());
    }
    // Set at each draw: range and spread may change after the sampler was made.
    bridge_sampler_->setStdDev(narrow_passage_spread_ > 0.0 ? narrow_passage_spread_ : range_);
    // Where no passage is known (nothing invalid nearby) the test fails: sample uniformly.
    if (bridge_sampler_->sample(random_state)) return;
  }
  sampler_->sampleUniform(random_state);
}

double OnlineRRTstar::nearRadius() const {
  const double n = static_cast<double>(nn_->size() + 1);
  return std::min(range_, rewire_factor_ * rrt_star_gamma_ *
                              std::pow(std::log(n) / n, 1.0 / effective_dimension_));
}

OnlineRRTstar::Node* OnlineRRTstar::extend(const ob::State* random_state) {
  Node query;
  query.state = const_cast<ob::State*>(random_state);
  Node* nearest = nn_->nearest(&query);
  const double distance = si_->distance(nearest->state, random_state);
  if (distance <= 0.0) return nullptr;
  ob::State* new_state = si_->allocState();
  if (distance > range_) {
    si_->getStateSpace()->interpolate(nearest->state, random_state, range_ / distance, new_state);
  } else {
    si_->copyState(new_state, random_state);
  }
  // Steering within the climb limit (3-D): a sample high above its nearest node still grows
  // the tree by the climb it may take; thrown away, the tree would rarely rise at all.
  if (climb_limit_) {
    climb_limit_->limitClimb(nearest->state, new_state);
    if (si_->distance(nearest->state, new_state) < 1e-3) {
      si_->freeState(new_state);
      return nullptr;
    }
  }
  if (!si_->isValid(new_state) || !si_->checkMotion(nearest->state, new_state)) {
    si_->freeState(new_state);
    return nullptr;  // TRAPPED
  }
  auto* node = new Node;
  node->state = new_state;
  std::vector<Node*> near;
  nn_->nearestR(node, nearRadius(), near);

  // Choose the parent: cheapest cost-to-come among the near nodes with a valid motion.
  node->parent = nearest;
  node->incoming_cost = objective_->motionCost(nearest->state, new_state);
  node->cost = objective_->combineCosts(nearest->cost, node->incoming_cost);
  std::vector<std::pair<ob::Cost, Node*>> candidates;
  for (Node* candidate : near) {
    if (candidate == nearest) continue;
    const ob::Cost incoming = objective_->motionCost(candidate->state, new_state);
    candidates.emplace_back(incoming, candidate);
  }
  std::sort(candidates.begin(), candidates.end(), [this](const auto& a, const auto& b) {
    return objective_->isCostBetterThan(objective_->combineCosts(a.second->cost, a.first),
                                        objective_->combineCosts(b.second->cost, b.first));
  });
  for (const auto& [incoming, candidate] : candidates) {
    const ob::Cost total = objective_->combineCosts(candidate->cost, incoming);
    if (!objective_->isCostBetterThan(total, node->cost)) break;  // sorted: none better
    if (si_->checkMotion(candidate->state, new_state)) {
      node->parent = candidate;
      node->incoming_cost = incoming;
      node->cost = total;
      break;
    }
  }
  node->parent->children.push_back(node);
  nn_->add(node);

  // Rewire: near nodes that are cheaper to reach through the new node.
  for (Node* neighbour : near) {
    if (neighbour == node->parent || neighbour == root_) continue;
    const ob::Cost incoming = objective_->motionCost(new_state, neighbour->state);
    const ob::Cost total = objective_->combineCosts(node->cost, incoming);
    if (objective_->isCostBetterThan(total, neighbour->cost) &&
        si_->checkMotion(new_state, neighbour->state)) {
      detachFromParent(neighbour);
      neighbour->parent = node;
      neighbour->incoming_cost = incoming;
      node->children.push_back(neighbour);
      propagateCost(neighbour);
    }
  }
  return node;
}

void OnlineRRTstar::detachFromParent(Node* node) {
  if (node->parent == nullptr) return;
  auto& siblings = node->parent->children;
  siblings.erase(std::remove(siblings.begin(), siblings.end(), node), siblings.end());
  node->parent = nullptr;
}

void OnlineRRTstar::propagateCost(Node* node) {
  std::vector<Node*> stack{node};
  while (!stack.empty()) {
    Node* current = stack.back();
    stack.pop_back();
    current->cost = current->parent
                        ? objective_->combineCosts(current->parent->cost, current->incoming_cost)
                        : objective_->identityCost();
    stack.insert(stack.end(), current->children.begin(), current->children.end());
  }
}

bool OnlineRRTstar::reachesGoal(const Node* node) const {
  return si_->distance(node->state, goal_state_) < goal_tolerance_;
}

ob::Cost OnlineRRTstar::costToGoal(const Node* node) const {
  return objective_->combineCosts(node->cost, objective_->motionCost(node->state, goal_state_));
}

const OnlineRRTstar::Node* OnlineRRTstar::bestSolution() const {
  const Node* best = nullptr;
  ob::Cost best_cost;
  for (const Node* candidate : solutions_) {
    const ob::Cost cost = costToGoal(candidate);
    if (best == nullptr || objective_->isCostBetterThan(cost, best_cost)) {
      best = candidate;
      best_cost = cost;
    }
  }
  return best;
}

ob::Cost OnlineRRTstar::bestCost() const {
  const Node* best = bestSolution();
  if (best == nullptr) return ob::Cost(std::numeric_limits<double>::infinity());
  return costToGoal(best);
}

std::vector<const ob::State*> OnlineRRTstar::bestPath() const {
  std::vector<const ob::State*> path;
  for (const Node* node = bestSolution(); node != nullptr; node = node->parent) {
    path.push_back(node->state);
  }
  std::reverse(path.begin(), path.end());
  return path;
}

void OnlineRRTstar::postSolution(bool approximate) {
  auto path = std::make_shared<ompl::geometric::PathGeometric>(si_);
  for (const ob::State* state : bestPath()) path->append(state);
  if (si_->distance(path->getStates().back(), goal_state_) > 0.0 &&
      si_->checkMotion(path->getStates().back(), goal_state_)) {
    path->append(goal_state_);
  }
  double distance_to_goal = 0.0;
  const bool satisfied = pdef_->getGoal()->isSatisfied(path->getStates().back(), &distance_to_goal);
  // One path, the current best: earlier ones may run through pruned or repaired parts of the
  // tree, and OMPL would keep (and sort) every one posted over a long mission.
  pdef_->clearSolutionPaths();
  pdef_->addSolutionPath(path, approximate || !satisfied, distance_to_goal, getName());
}

bool OnlineRRTstar::popWaypoint(ob::State* waypoint) {
  const Node* best = bestSolution();
  if (best == nullptr || best == root_) return false;
  Node* next = const_cast<Node*>(best);
  while (next->parent != root_) next = next->parent;
  si_->copyState(waypoint, next->state);
  // The old root and every subtree but next's go.
  Node* old_root = root_;
  detachFromParent(next);
  root_ = next;
  root_->incoming_cost = objective_->identityCost();
  propagateCost(root_);
  std::vector<Node*> removed;
  detachSubtree(old_root, removed);
  discard(removed);
  return true;
}

UpdateResult OnlineRRTstar::updateTree(const ob::State* vehicle_state) {
  return recheckTree(vehicle_state, {});
}

UpdateResult OnlineRRTstar::updateTree(const ob::State* vehicle_state,
                                       const Eigen::AlignedBox3d& changed, double influence) {
  if (changed.isEmpty())
    return recheckTree(vehicle_state, [](const Node*, const Node*) { return false; });
  const Eigen::AlignedBox3d near_change(changed.min().array() - influence,
                                        changed.max().array() + influence);
  const auto position = [](const Node* node) {
    const auto* state = node->state->as<ob::RealVectorStateSpace::StateType>();
    return Eigen::Vector3d(state->values[0], state->values[1], state->values[2]);
  };
  return recheckTree(vehicle_state, [&](const Node* parent, const Node* child) {
    Eigen::AlignedBox3d edge(position(parent));
    edge.extend(position(child));
    return edge.intersects(near_change);
  });
}

UpdateResult OnlineRRTstar::recheckTree(
    const ob::State* vehicle_state, const std::function<bool(const Node*, const Node*)>& affected) {
  UpdateResult result;
  if (root_ == nullptr) return result;
  result.root_in_collision = !si_->isValid(root_->state);
  result.vehicle_to_root_blocked =
      vehicle_state != nullptr && !si_->checkMotion(vehicle_state, root_->state);
  // DFS from the root; a child whose state or edge collides goes with its whole subtree.
  // Edge costs are recomputed on the way since the objective depends on the map too; edges the
  // change cannot reach keep theirs, but their cost-to-come follows their parent's.
  std::vector<Node*> stack{root_};
  std::vector<Node*> colliding;
  std::vector<Node*> removed;
  while (!stack.empty()) {
    Node* node = stack.back();
    stack.pop_back();
    colliding.clear();
    for (Node* child : node->children) {
      if (!affected || affected(node, child)) {
        if (!si_->isValid(child->state) || !si_->checkMotion(node->state, child->state)) {
          colliding.push_back(child);
          continue;
        }
        child->incoming_cost = objective_->motionCost(node->state, child->state);
      }
      child->cost = objective_->combineCosts(node->cost, child->incoming_cost);
      stack.push_back(child);
    }
    for (Node* child : colliding) detachSubtree(child, removed);
  }
  result.removed_nodes = removed.size();
  discard(removed);
  return result;
}

void OnlineRRTstar::detachSubtree(Node* subtree_root, std::vector<Node*>& removed) {
  detachFromParent(subtree_root);
  std::vector<Node*> stack{subtree_root};
  while (!stack.empty()) {
    Node* node = stack.back();
    stack.pop_back();
    removed.push_back(node);
    stack.insert(stack.end(), node->children.begin(), node->children.end());
  }
}

void OnlineRRTstar::discard(const std::vector<Node*>& removed) {
  if (removed.empty()) return;
  // One rebuild: removing nodes one by one from OMPL's GNAT rebuilds it whenever a removed
  // node is a pivot, dozens of times for one obstacle (measured by bench/update_bench).
  reindex();  // walks the tree from root_, which no longer reaches the removed nodes
  for (Node* node : removed) {
    si_->freeState(node->state);
    delete node;
  }
}

void OnlineRRTstar::reset(const ob::State* root_state) {
  if (!isSetup()) setup();
  freeTree();
  addRoot(root_state);
}

void OnlineRRTstar::reindex() {
  std::vector<Node*> nodes;
  std::vector<Node*> stack{root_};
  while (!stack.empty()) {
    Node* node = stack.back();
    stack.pop_back();
    nodes.push_back(node);
    stack.insert(stack.end(), node->children.begin(), node->children.end());
  }
  nn_->clear();
  nn_->add(nodes);
  solutions_.clear();
  if (goal_state_) {
    for (Node* node : nodes) {
      if (reachesGoal(node)) solutions_.push_back(node);
    }
  }
}

bool OnlineRRTstar::checkConsistency() const {
  if (root_ == nullptr) return nn_->size() == 0 && solutions_.empty();
  if (root_->parent != nullptr) return false;
  std::unordered_set<const Node*> in_tree;
  std::vector<const Node*> stack{root_};
  auto close = [](double a, double b) {
    return std::abs(a - b) <= kCostTolerance * std::max(1.0, std::abs(a));
  };
  while (!stack.empty()) {
    const Node* node = stack.back();
    stack.pop_back();
    if (!in_tree.insert(node).second) return false;  // reached twice: a cycle or shared child
    const double expected =
        node->parent ? objective_->combineCosts(node->parent->cost, node->incoming_cost).value()
                     : objective_->identityCost().value();
    if (!close(node->cost.value(), expected)) return false;
    if (node->parent && !close(node->incoming_cost.value(),
                               objective_->motionCost(node->parent->state, node->state).value())) {
      return false;
    }
    for (const Node* child : node->children) {
      if (child->parent != node) return false;
      stack.push_back(child);
    }
  }
  std::vector<Node*> indexed;
  nn_->list(indexed);
  if (indexed.size() != in_tree.size()) return false;
  for (const Node* node : indexed) {
    if (in_tree.count(node) == 0) return false;
  }
  for (const Node* node : solutions_) {
    if (in_tree.count(node) == 0) return false;
  }
  return true;
}

void OnlineRRTstar::snapshot(TreeSnapshot& tree) const {
  const Node* best = bestSolution();
  // Depth-first from the root: a parent always gets its index before its children.
  std::vector<std::pair<const Node*, int32_t>> stack;
  if (root_) stack.emplace_back(root_, -1);
  while (!stack.empty()) {
    const auto [node, parent] = stack.back();
    stack.pop_back();
    const auto index = static_cast<int32_t>(tree.nodes.size());
    const auto* values = node->state->as<ob::RealVectorStateSpace::StateType>()->values;
    tree.nodes.emplace_back(values[0], values[1], values[2]);
    tree.parents.push_back(parent);
    tree.costs.push_back(node->cost.value());
    if (parent < 0) tree.root_index = index;
    if (node == best) tree.best_solution_index = index;
    for (const Node* child : node->children) stack.emplace_back(child, index);
  }
}

void OnlineRRTstar::getPlannerData(ob::PlannerData& data) const {
  ob::Planner::getPlannerData(data);
  if (root_ == nullptr) return;
  std::unordered_set<const Node*> solution_set(solutions_.begin(), solutions_.end());
  std::vector<const Node*> stack{root_};
  while (!stack.empty()) {
    const Node* node = stack.back();
    stack.pop_back();
    if (node == root_) {
      data.addStartVertex(ob::PlannerDataVertex(node->state));
    } else if (solution_set.count(node) > 0) {
      data.addGoalVertex(ob::PlannerDataVertex(node->state));
    } else {
      data.addVertex(ob::PlannerDataVertex(node->state));
    }
    if (node->parent) {
      data.addEdge(ob::PlannerDataVertex(node->parent->state), ob::PlannerDataVertex(node->state));
    }
    stack.insert(stack.end(), node->children.begin(), node->children.end());
  }
}

std::shared_ptr<OnlineRRTstar> makeOnlineRRTstar(const TreeSettings& settings,
                                                 const ob::SpaceInformationPtr& si,
                                                 const ob::ProblemDefinitionPtr& pdef,
                                                 const ob::State* root) {
  auto planner = std::make_shared<OnlineRRTstar>(si);
  planner->setRange(settings.range);
  planner->setGoalBias(settings.goal_bias);
  planner->setNarrowPassageBias(settings.narrow_passage_bias);
  planner->setRewireFactor(settings.rewire_factor);
  planner->setGoalTolerance(settings.goal_tolerance);
  planner->setProblemDefinition(pdef);
  planner->setup();
  planner->reset(root);
  return planner;
}

}  // namespace auv::planning
