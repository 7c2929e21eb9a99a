#include "bench_common.h"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <thread>

#include <ompl/base/ScopedState.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/planners/informedtrees/BITstar.h>
#include <ompl/geometric/planners/rrt/InformedRRTstar.h>
#include <ompl/geometric/planners/rrt/RRTstar.h>
#include <yaml-cpp/yaml.h>

#include "auv/planning/components/planning_component.h"
#include "auv/planning/online_rrt_star.h"

namespace auv::planning::bench {
namespace ob = ompl::base;
namespace og = ompl::geometric;

namespace {

Eigen::Vector3d readPoint(const YAML::Node& node, const std::string& where) {
  if (!node.IsSequence() || node.size() != 3) {
    throw std::runtime_error(where + ": expected [x, y, z] (m NED)");
  }
  try {
    return {node[0].as<double>(), node[1].as<double>(), node[2].as<double>()};
  } catch (const YAML::Exception&) {
    throw std::runtime_error(where + ": expected three numbers");
  }
}

}  // namespace

BenchScenario readScenario(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(path + ": cannot read the scenario (" + e.what() + ")");
  }
  BenchScenario scenario;
  scenario.file = path;
  scenario.name =
      root["name"] ? root["name"].as<std::string>() : std::filesystem::path(path).stem().string();
  if (root["world"] && root["world"]["seabed_depth"]) {
    scenario.seabed_depth = root["world"]["seabed_depth"].as<double>();
  }
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  if (root["vehicle"] && root["vehicle"]["start"] && root["vehicle"]["start"]["position"]) {
    position = readPoint(root["vehicle"]["start"]["position"], path + ": vehicle.start.position");
  }
  const YAML::Node queries = root["queries"];
  if (!queries || !queries.IsSequence() || queries.size() == 0) {
    throw std::runtime_error(path + ": queries: the scenario has no queries");
  }
  for (std::size_t i = 0; i < queries.size(); ++i) {
    const std::string where = path + ": queries[" + std::to_string(i) + "]";
    BenchQuery query;
    query.name =
        queries[i]["name"] ? queries[i]["name"].as<std::string>() : "query" + std::to_string(i + 1);
    if (!queries[i]["goal"]) throw std::runtime_error(where + ".goal: missing");
    query.goal = readPoint(queries[i]["goal"], where + ".goal");
    if (queries[i]["tolerance"]) query.tolerance = queries[i]["tolerance"].as<double>();
    query.start = position;
    position = query.goal;
    scenario.queries.push_back(query);
  }
  return scenario;
}

PlannerSettings PlannerSettings::componentDefaults() {
  const PlanningComponent::Options component;
  PlannerSettings settings;
  settings.range = component.range;
  settings.goal_bias = component.goal_bias;
  settings.narrow_passage_bias = component.narrow_passage_bias;
  settings.rewire_factor = component.rewire_factor;
  settings.clearance = component.clearance;
  settings.visibility_weight = component.visibility_weight;
  settings.max_distance = component.max_distance;
  settings.cost.expected_distance = 1.0;
  settings.cost.admissible_range = 1.0;
  settings.fixed_depth = true;
  return settings;
}

std::string PlannerSettings::describe() const {
  std::ostringstream out;
  out << "range " << range << " m, goal bias " << goal_bias << ", narrow-passage bias "
      << narrow_passage_bias << " (OnlineRRTstar), rewire factor " << rewire_factor
      << ", clearance " << clearance.clearance() << " m (hull " << clearance.hull_radius
      << " + margin " << clearance.safety_margin << "), visibility objective d_e "
      << cost.expected_distance << " m, Δd_a " << cost.admissible_range << " m, weight "
      << visibility_weight << ", distance clamp " << max_distance << " m, "
      << (fixed_depth ? "fixed depth (the query's start depth)" : "3-D (surface to seabed)");
  return out.str();
}

WorldMap loadWorldMap(const std::string& bt_path, double max_distance) {
  const auto started = Clock::now();
  if (!std::filesystem::is_regular_file(bt_path)) {
    throw std::runtime_error(bt_path + ": no such map file");
  }
  WorldMap map;
  map.tree = std::make_unique<octomap::OcTree>(0.1);
  if (!map.tree->readBinary(bt_path) || map.tree->size() == 0) {
    throw std::runtime_error(bt_path + ": not a readable OctoMap .bt file");
  }
  map.tree->getMetricMin(map.min_corner.x(), map.min_corner.y(), map.min_corner.z());
  map.tree->getMetricMax(map.max_corner.x(), map.max_corner.y(), map.max_corner.z());
  OctomapDistanceFieldOptions options;
  options.max_distance = max_distance;
  options.min_corner = map.min_corner;
  options.max_corner = map.max_corner;
  map.field = std::make_shared<OctomapDistanceField>(map.tree.get(), options);
  map.build_seconds = secondsSince(started);
  return map;
}

void QueryProblem::setPosition(ob::State* state, const Eigen::Vector3d& position) const {
  auto* values = state->as<ob::RealVectorStateSpace::StateType>()->values;
  for (int i = 0; i < 3; ++i) values[i] = position[i];
}

ob::ProblemDefinitionPtr QueryProblem::makeProblemDefinition() const {
  ob::ScopedState<> start_state(si), goal_state(si);
  setPosition(start_state.get(), start);
  setPosition(goal_state.get(), goal);
  auto pdef = std::make_shared<ob::ProblemDefinition>(si);
  pdef->setStartAndGoalStates(start_state, goal_state, tolerance);
  pdef->setOptimizationObjective(objective);
  return pdef;
}

double QueryProblem::costToGoal(const std::vector<const ob::State*>& states) const {
  if (states.empty()) return std::numeric_limits<double>::infinity();
  ob::Cost total = objective->identityCost();
  for (std::size_t i = 1; i < states.size(); ++i) {
    total = objective->combineCosts(total, objective->motionCost(states[i - 1], states[i]));
  }
  ob::ScopedState<> goal_state(si);
  setPosition(goal_state.get(), goal);
  total = objective->combineCosts(total, objective->motionCost(states.back(), goal_state.get()));
  return total.value();
}

QueryProblem makeQueryProblem(const WorldMap& map, const BenchQuery& query,
                              const PlannerSettings& settings, double seabed_depth) {
  QueryProblem problem;
  PlanningSpaceOptions space;
  space.min_corner = {map.min_corner.x(), map.min_corner.y(), 0.0};
  space.max_corner = {map.max_corner.x(), map.max_corner.y(),
                      std::min(seabed_depth, map.max_corner.z())};
  problem.start = query.start;
  problem.goal = query.goal;
  if (settings.fixed_depth) {
    problem.fixed_depth = query.start.z();
    space.fixed_depth = query.start.z();
    problem.goal.z() = query.start.z();
  }
  problem.tolerance = query.tolerance;
  problem.si = makeSpaceInformation(space, map.field, settings.clearance);
  VisibilityObjectiveOptions visibility;
  visibility.cost = settings.cost;
  visibility.visibility_weight = settings.visibility_weight;
  problem.objective = std::make_shared<VisibilityObjective>(problem.si, map.field, visibility);
  return problem;
}

const std::vector<std::string>& plannerNames() {
  static const std::vector<std::string> names = {"OnlineRRTstar", "RRTstar", "InformedRRTstar",
                                                 "BITstar"};
  return names;
}

ob::PlannerPtr makePlanner(const std::string& name, const QueryProblem& problem,
                           const PlannerSettings& settings) {
  if (name == "OnlineRRTstar") {
    auto planner = std::make_shared<OnlineRRTstar>(problem.si);
    planner->setRange(settings.range);
    planner->setGoalBias(settings.goal_bias);
    planner->setNarrowPassageBias(settings.narrow_passage_bias);
    planner->setRewireFactor(settings.rewire_factor);
    planner->setGoalTolerance(problem.tolerance);
    return planner;
  }
  if (name == "RRTstar" || name == "InformedRRTstar") {
    std::shared_ptr<og::RRTstar> planner = name == "RRTstar"
                                               ? std::make_shared<og::RRTstar>(problem.si)
                                               : std::make_shared<og::InformedRRTstar>(problem.si);
    planner->setRange(settings.range);
    planner->setGoalBias(settings.goal_bias);
    planner->setRewireFactor(settings.rewire_factor);
    return planner;
  }
  if (name == "BITstar") return std::make_shared<og::BITstar>(problem.si);
  throw std::invalid_argument("unknown planner '" + name +
                              "' (OnlineRRTstar, RRTstar, InformedRRTstar, BITstar)");
}

double percentile(std::vector<double> values, double q) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(values.begin(), values.end());
  const double position = std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size() - 1);
  const auto low = static_cast<std::size_t>(std::floor(position));
  const auto high = static_cast<std::size_t>(std::ceil(position));
  const double fraction = position - static_cast<double>(low);
  if (fraction == 0.0 || low == high) return values[low];
  if (std::isinf(values[high])) return values[high];
  return values[low] + fraction * (values[high] - values[low]);
}

std::string machineNote() {
  std::ifstream file("/proc/loadavg");
  double one = 0, five = 0, fifteen = 0;
  file >> one >> five >> fifteen;
  std::ostringstream out;
  out << std::thread::hardware_concurrency() << " CPUs, load average " << one << " " << five << " "
      << fifteen;
  return out.str();
}

std::string timestamp() {
  const std::time_t now = std::time(nullptr);
  std::tm local{};
  localtime_r(&now, &local);
  char text[32];
  std::strftime(text, sizeof(text), "%Y%m%d_%H%M%S", &local);
  return text;
}

std::string formatNumber(double value, int digits, const std::string& infinite) {
  if (std::isnan(value)) return "—";
  if (std::isinf(value)) return infinite;
  std::ostringstream out;
  out << std::fixed << std::setprecision(digits) << value;
  return out.str();
}

}  // namespace auv::planning::bench
