#include "auv/planning/waypoint_planner.h"

#include "auv/planning/distance_field.h"
#include "auv/planning/online_rrt_star.h"
#include "auv/planning/scratch_planner.h"

namespace auv::planning {

Replanning replanningFromName(const std::string& name) {
  if (name == "repair") return Replanning::REPAIR;
  if (name == "scratch") return Replanning::SCRATCH;
  if (name == "restart") return Replanning::RESTART;
  throw PlanningConfigError("replanning: expected one of repair, scratch, restart, got '" + name +
                            "'");
}

std::shared_ptr<WaypointPlanner> makeWaypointPlanner(Replanning mode, const TreeSettings& settings,
                                                     const ompl::base::SpaceInformationPtr& si,
                                                     const ompl::base::ProblemDefinitionPtr& pdef,
                                                     const ompl::base::State* root) {
  if (mode == Replanning::REPAIR) return makeOnlineRRTstar(settings, si, pdef, root);
  auto planner = std::make_shared<ScratchPlanner>(si, pdef, settings, mode);
  planner->reset(root);
  return planner;
}

}  // namespace auv::planning
