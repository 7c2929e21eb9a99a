#include "auv/mission/mission_plan.h"

#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>

namespace auv::mission {
namespace {

const std::set<std::string> kQueryKeys = {"name",
                                          "goal",
                                          "goal_tolerance",
                                          "time_budget",
                                          "objective",
                                          "expected_distance",
                                          "admissible_range",
                                          "bounds",
                                          "fixed_depth",
                                          "depth"};

std::string where(const std::string& source, const std::string& context, const std::string& key) {
  return source + ": " + context + (key.empty() ? "" : "." + key);
}

void rejectUnknownKeys(const YAML::Node& node, const std::set<std::string>& allowed,
                       const std::string& context) {
  for (const auto& entry : node) {
    const std::string key = entry.first.as<std::string>();
    if (allowed.count(key) == 0) {
      std::string list;
      for (const auto& name : allowed) list += (list.empty() ? "" : ", ") + name;
      throw MissionError(context + ": unknown field '" + key + "' (known: " + list + ")");
    }
  }
}

template <class T>
T read(const YAML::Node& node, const std::string& context) {
  try {
    return node.as<T>();
  } catch (const YAML::Exception&) {
    throw MissionError(context + ": '" + YAML::Dump(node) + "' is not a valid " +
                       (std::is_same_v<T, bool>     ? "boolean"
                        : std::is_same_v<T, double> ? "number"
                                                    : "string"));
  }
}

Eigen::Vector3d readPoint(const YAML::Node& node, const std::string& context) {
  if (!node.IsSequence() || node.size() != 3) {
    throw MissionError(context + ": expected [north, east, down] in metres");
  }
  return {read<double>(node[0], context + "[0]"), read<double>(node[1], context + "[1]"),
          read<double>(node[2], context + "[2]")};
}

/// Fields of `node` override those of `query` (defaults, then the query's own).
void readQueryFields(const YAML::Node& node, const std::string& context, MissionQuery& query) {
  if (!node.IsMap()) throw MissionError(context + ": expected a map of fields");
  rejectUnknownKeys(node, kQueryKeys, context);
  auto field = [&](const char* key) { return context + "." + key; };
  if (node["name"]) query.name = read<std::string>(node["name"], field("name"));
  if (node["goal"]) query.goal = readPoint(node["goal"], field("goal"));
  if (node["goal_tolerance"]) {
    query.goal_tolerance = read<double>(node["goal_tolerance"], field("goal_tolerance"));
  }
  if (node["time_budget"])
    query.time_budget = read<double>(node["time_budget"], field("time_budget"));
  if (node["objective"]) {
    const std::string objective = read<std::string>(node["objective"], field("objective"));
    if (objective != "visibility" && objective != "path_length") {
      throw MissionError(field("objective") + ": '" + objective +
                         "' is not one of visibility, path_length");
    }
    query.visibility_objective = objective == "visibility";
  }
  if (node["expected_distance"]) {
    query.expected_distance = read<double>(node["expected_distance"], field("expected_distance"));
  }
  if (node["admissible_range"]) {
    query.admissible_range = read<double>(node["admissible_range"], field("admissible_range"));
  }
  if (node["bounds"]) {
    const YAML::Node bounds = node["bounds"];
    if (!bounds.IsMap() || !bounds["min"] || !bounds["max"] || bounds.size() != 2) {
      throw MissionError(field("bounds") + ": expected {min: [n, e, d], max: [n, e, d]}");
    }
    query.bounds_min = readPoint(bounds["min"], field("bounds") + ".min");
    query.bounds_max = readPoint(bounds["max"], field("bounds") + ".max");
  }
  if (node["fixed_depth"])
    query.fixed_depth = read<bool>(node["fixed_depth"], field("fixed_depth"));
  if (node["depth"]) query.depth = read<double>(node["depth"], field("depth"));
}

/// `text` as a double-quoted YAML scalar (names may hold '#', ': ', quotes, backslashes).
std::string quoted(const std::string& text) {
  YAML::Emitter out;
  out << YAML::DoubleQuoted << text;
  return out.c_str();
}

std::string vectorYaml(const Eigen::Vector3d& v) {
  std::ostringstream out;
  out.precision(10);
  out << "[" << v.x() << ", " << v.y() << ", " << v.z() << "]";
  return out.str();
}

}  // namespace

void checkQuery(const MissionQuery& q, const std::string& source) {
  const std::string context = source + ": query '" + q.name + "'";
  auto fail = [&](const std::string& field, const std::string& why) {
    throw MissionError(context + " " + field + ": " + why);
  };
  if (!q.goal.allFinite()) fail("goal", "not finite");
  if (!q.bounds_min.allFinite() || !q.bounds_max.allFinite()) fail("bounds", "not finite");
  if (!(q.goal_tolerance > 0.0) || !std::isfinite(q.goal_tolerance)) {
    fail("goal_tolerance", "must be > 0 m");
  }
  if (!(q.time_budget >= 0.0) || !std::isfinite(q.time_budget)) {
    fail("time_budget", "must be >= 0 s (0 = planner default)");
  }
  if (!(q.expected_distance >= 0.0) || !std::isfinite(q.expected_distance)) {
    fail("expected_distance", "must be >= 0 m");
  }
  if (!(q.admissible_range >= 0.0) || !std::isfinite(q.admissible_range)) {
    fail("admissible_range", "must be >= 0 m");
  }
  for (int axis = 0; axis < 3; ++axis) {
    // A fixed-depth query may give a flat z range: only the plane is sampled.
    const bool flat_ok = axis == 2 && q.fixed_depth;
    if (q.bounds_max[axis] < q.bounds_min[axis] ||
        (!flat_ok && q.bounds_max[axis] == q.bounds_min[axis])) {
      fail("bounds", "max must exceed min on every axis (axis " + std::to_string(axis) + ")");
    }
  }
  Eigen::Vector3d goal = q.goal;
  if (q.fixed_depth && q.depth) goal.z() = *q.depth;
  const bool inside_horizontally =
      (goal.head<2>().array() >= q.bounds_min.head<2>().array()).all() &&
      (goal.head<2>().array() <= q.bounds_max.head<2>().array()).all();
  const bool inside_vertically =
      q.fixed_depth || (goal.z() >= q.bounds_min.z() && goal.z() <= q.bounds_max.z());
  if (!inside_horizontally || !inside_vertically) {
    fail("goal", vectorYaml(goal) + " is outside the bounds " + vectorYaml(q.bounds_min) + " .. " +
                     vectorYaml(q.bounds_max));
  }
  if (q.depth && (!std::isfinite(*q.depth) || *q.depth < 0.0)) {
    fail("depth", "must be >= 0 m (positive down)");
  }
  if (!q.fixed_depth && goal.z() < 0.0) fail("goal", "is above the surface (z < 0)");
}

MissionPlan parseMission(const std::string& yaml_text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& error) {
    throw MissionError(source + ": malformed YAML at line " + std::to_string(error.mark.line + 1) +
                       ": " + error.msg);
  }
  if (!root.IsMap() || !root["mission"]) {
    throw MissionError(source + ": expected a top-level 'mission:' section");
  }
  const YAML::Node mission = root["mission"];
  rejectUnknownKeys(mission, {"name", "defaults", "queries"}, source + ": mission");
  MissionPlan plan;
  plan.name = mission["name"] ? read<std::string>(mission["name"], where(source, "mission", "name"))
                              : "mission";
  MissionQuery defaults;
  if (mission["defaults"]) {
    readQueryFields(mission["defaults"], where(source, "mission", "defaults"), defaults);
  }
  const YAML::Node queries = mission["queries"];
  if (!queries || !queries.IsSequence() || queries.size() == 0) {
    throw MissionError(where(source, "mission", "queries") + ": expected a non-empty list");
  }
  for (std::size_t i = 0; i < queries.size(); ++i) {
    MissionQuery query = defaults;
    query.name = "query " + std::to_string(i + 1);
    const std::string context = where(source, "mission", "queries[" + std::to_string(i) + "]");
    if (queries[i].IsMap() && !queries[i]["goal"]) throw MissionError(context + ": no goal");
    readQueryFields(queries[i], context, query);
    checkQuery(query, source);
    plan.queries.push_back(query);
  }
  return plan;
}

MissionPlan loadMissionFile(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw MissionError(path + ": cannot read the mission file");
  std::stringstream text;
  text << file.rdbuf();
  return parseMission(text.str(), path);
}

std::string toYaml(const MissionPlan& plan) {
  std::ostringstream out;
  out.precision(10);
  out << "mission:\n  name: " << quoted(plan.name) << "\n  queries:\n";
  for (const MissionQuery& q : plan.queries) {
    out << "    - name: " << quoted(q.name) << "\n"
        << "      goal: " << vectorYaml(q.goal) << "\n"
        << "      goal_tolerance: " << q.goal_tolerance << "\n"
        << "      time_budget: " << q.time_budget << "\n"
        << "      objective: " << (q.visibility_objective ? "visibility" : "path_length") << "\n"
        << "      expected_distance: " << q.expected_distance << "\n"
        << "      admissible_range: " << q.admissible_range << "\n"
        << "      bounds: {min: " << vectorYaml(q.bounds_min)
        << ", max: " << vectorYaml(q.bounds_max) << "}\n"
        << "      fixed_depth: " << (q.fixed_depth ? "true" : "false") << "\n";
    if (q.depth) out << "      depth: " << *q.depth << "\n";
  }
  return out.str();
}

msg::PlannerQuery toPlannerQuery(const MissionQuery& q) {
  msg::PlannerQuery query;
  query.header().frame_id("world");
  query.goal().position().x(q.goal.x());
  query.goal().position().y(q.goal.y());
  query.goal().position().z(q.goal.z());
  query.goal().orientation().w(1.0);
  query.goal_tolerance(q.goal_tolerance);
  query.time_budget(q.time_budget);
  query.objective(q.visibility_objective ? msg::PLANNER_OBJECTIVE_VISIBILITY_COST
                                         : msg::PLANNER_OBJECTIVE_PATH_LENGTH);
  query.expected_distance(q.expected_distance);
  query.admissible_range(q.admissible_range);
  query.bounds_min().x(q.bounds_min.x());
  query.bounds_min().y(q.bounds_min.y());
  query.bounds_min().z(q.bounds_min.z());
  query.bounds_max().x(q.bounds_max.x());
  query.bounds_max().y(q.bounds_max.y());
  query.bounds_max().z(q.bounds_max.z());
  query.fixed_depth(q.fixed_depth);
  // On the wire an unset depth is NaN: the mission handler fills in the vehicle's depth.
  query.depth(q.depth ? *q.depth : std::numeric_limits<double>::quiet_NaN());
  return query;
}

MissionQuery fromPlannerQuery(const msg::PlannerQuery& query, std::size_t index) {
  MissionQuery q;
  q.name = "query " + std::to_string(index + 1);
  const auto& goal = query.goal().position();
  q.goal = {goal.x(), goal.y(), goal.z()};
  q.goal_tolerance = query.goal_tolerance();
  q.time_budget = query.time_budget();
  q.visibility_objective = query.objective() != msg::PLANNER_OBJECTIVE_PATH_LENGTH;
  q.expected_distance = query.expected_distance();
  q.admissible_range = query.admissible_range();
  q.bounds_min = {query.bounds_min().x(), query.bounds_min().y(), query.bounds_min().z()};
  q.bounds_max = {query.bounds_max().x(), query.bounds_max().y(), query.bounds_max().z()};
  q.fixed_depth = query.fixed_depth();
  if (!std::isnan(query.depth())) q.depth = query.depth();
  return q;
}

}  // namespace auv::mission
