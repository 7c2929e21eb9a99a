#include "auv/planning/waypoint_planner.h"

#include "auv/planning/distance_field.h"
#include "auv/planning/online_rrt_star.h"
#include "auv/planning/scratch_planner.h"

namespace auv::planning {

Replanning replanningFromName(const std::string& name) {
  if (name == "repair") return Replanning::REPAIR;
  if (name == "scratch") return Replanning::SCRATCH;
  throw PlanningConfigError("replanning: expected one of repair, scratch, got '" + name + "'");
}

std::shared_ptr<WaypointPlanner> makeWaypointPlanner(Replanning mode, const TreeSettings& settings,
                                                     const ompl::base::SpaceInformationPtr& si,
                                                     const ompl::base::ProblemDefinitionPtr& pdef,
                                                     const ompl::base::State* root) {
  if (mode == Replanning::SCRATCH) {
    auto planner = std::make_shared<ScratchPlanner>(si, pdef, settings);
    planner->reset(root);
    return planner;
  }
  auto planner = std::make_shared<OnlineRRTstar>(si);
  planner->setRange(settings.range);
  planner->setGoalBias(settings.goal_bias);
  planner->setNarrowPassageBias(settings.narrow_passage_bias);
  planner->setRewireFactor(settings.rewire_factor);
  planner->setGoalTolerance(settings.goal_tolerance);
  planner->setProblemDefinition(pdef);
  planner->setup();
  // Root the tree at the start even when it is inside the clearance (a vehicle that drifted
  // close to a wall): OMPL's start-state input skips invalid starts and would leave no tree,
  // while the motion validator lets the tree leave such a root by moving away from the wall.
  planner->reset(root);
  return planner;
}

}  // namespace auv::planning
