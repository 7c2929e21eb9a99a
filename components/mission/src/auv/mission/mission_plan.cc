#include "auv/mission/mission_plan.h"

#include <charconv>
#include <cmath>
#include <limits>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "auv/config/yaml_section.h"

namespace auv::mission {
namespace {

using config::YamlSection;

const std::vector<std::string> kQueryKeys = {"name",
                                             "goal",
                                             "goal_tolerance",
                                             "time_budget",
                                             "objective",
                                             "expected_distance",
                                             "admissible_range",
                                             "bounds",
                                             "fixed_depth",
                                             "depth",
                                             "min_depth",
                                             "max_depth",
                                             "min_altitude"};

/// A point [north, east, down] in metres under `key`, when present.
void readPoint(const YamlSection& section, const std::string& key, Eigen::Vector3d& point) {
  if (!section.has(key)) return;
  const YAML::Node node = section.node()[key];
  if (!node.IsSequence() || node.size() != 3) {
    section.fail(key, "expected [north, east, down] in metres");
  }
  section.read(key, point);
}

/// A number under `key`, when present.
void readOptional(const YamlSection& section, const std::string& key,
                  std::optional<double>& value) {
  if (!section.has(key)) return;
  double read = 0.0;
  section.read(key, read);
  value = read;
}

/// Fields of `section` override those of `query` (defaults, then the query's own).
void readQueryFields(const YamlSection& section, MissionQuery& query) {
  section.rejectUnknownKeys(kQueryKeys);
  section.read("name", query.name);
  readPoint(section, "goal", query.goal);
  section.read("goal_tolerance", query.goal_tolerance);
  section.read("time_budget", query.time_budget);
  if (section.has("objective")) {
    std::string objective;
    section.read("objective", objective);
    if (objective != "visibility" && objective != "path_length") {
      section.fail("objective", "'" + objective + "' is not one of visibility, path_length");
    }
    query.visibility_objective = objective == "visibility";
  }
  section.read("expected_distance", query.expected_distance);
  section.read("admissible_range", query.admissible_range);
  if (section.has("bounds")) {
    const YAML::Node bounds = section.node()["bounds"];
    if (!bounds.IsMap() || !bounds["min"] || !bounds["max"] || bounds.size() != 2) {
      section.fail("bounds", "expected {min: [n, e, d], max: [n, e, d]}");
    }
    readPoint(section.child("bounds"), "min", query.bounds_min);
    readPoint(section.child("bounds"), "max", query.bounds_max);
  }
  section.read("fixed_depth", query.fixed_depth);
  readOptional(section, "depth", query.depth);
  readOptional(section, "min_depth", query.min_depth);
  readOptional(section, "max_depth", query.max_depth);
  section.read("min_altitude", query.min_altitude);
}

/// The mission of a file's root section (the shared strict reader: ConfigError on bad input).
MissionPlan readMission(const YamlSection& root) {
  const std::string& source = root.file();
  if (!root.has("mission")) {
    throw MissionError(source + ": expected a top-level 'mission:' section");
  }
  const YamlSection mission = root.child("mission");
  mission.rejectUnknownKeys({"name", "defaults", "queries"});
  MissionPlan plan;
  plan.name = "mission";
  mission.read("name", plan.name);
  MissionQuery defaults;
  readQueryFields(mission.child("defaults"), defaults);
  const YAML::Node queries = mission.node()["queries"];
  if (!queries || !queries.IsSequence() || queries.size() == 0) {
    mission.fail("queries", "expected a non-empty list");
  }
  const std::vector<YamlSection> sections = mission.childList("queries");
  for (std::size_t i = 0; i < sections.size(); ++i) {
    MissionQuery query = defaults;
    query.name = "query " + std::to_string(i + 1);
    if (!sections[i].has("goal"))
      throw MissionError(source + ": " + sections[i].path() + ": no goal");
    readQueryFields(sections[i], query);
    checkQuery(query, source);
    plan.queries.push_back(query);
  }
  return plan;
}

/// Runs `read`, reporting the shared reader's ConfigError as the MissionError callers catch.
template <class Read>
MissionPlan asMissionError(Read read) {
  try {
    return read();
  } catch (const MissionError&) {
    throw;
  } catch (const config::ConfigError& error) {
    throw MissionError(error.what());
  }
}

/// `text` as a double-quoted YAML scalar (names may hold '#', ': ', quotes, backslashes).
std::string quoted(const std::string& text) {
  YAML::Emitter out;
  out << YAML::DoubleQuoted << text;
  return out.c_str();
}

/// The shortest text that reads back as exactly `value` (10 significant digits did not: a
/// mission whose bounds differ in the 12th digit was written as one with max == min, which the
/// resumed handler refused in progress.yaml); -0 as 0, which it reads back as.
std::string number(double value) {
  char text[32];
  const auto result = std::to_chars(text, text + sizeof(text), value == 0.0 ? 0.0 : value);
  return std::string(text, result.ptr);
}

std::string vectorYaml(const Eigen::Vector3d& v) {
  return "[" + number(v.x()) + ", " + number(v.y()) + ", " + number(v.z()) + "]";
}

std::string metres(double value) {
  std::ostringstream out;
  out << value << " m";
  return out.str();
}

/// The depth band's rules (checkQuery); `fail(field, why)` throws.
template <class Fail>
void checkBand(const MissionQuery& q, const Eigen::Vector3d& goal, Fail fail) {
  if (!q.min_depth && !q.max_depth) return;
  if (!q.min_depth) fail("max_depth", "given without min_depth (a band needs both)");
  if (!q.max_depth) fail("min_depth", "given without max_depth (a band needs both)");
  const double low = *q.min_depth, high = *q.max_depth;
  if (!std::isfinite(low) || low < 0.0) fail("min_depth", "must be >= 0 m (positive down)");
  if (!std::isfinite(high)) fail("max_depth", "not finite");
  if (q.fixed_depth) {
    fail("min_depth",
         "a depth band is for 3-D planning, and this query has fixed_depth: true "
         "(drop min_depth/max_depth or set fixed_depth: false)");
  }
  if (!(low < high)) {
    fail("min_depth", metres(low) + " must be shallower than max_depth " + metres(high));
  }
  const std::string z_range =
      " the bounds' z-range [" + metres(q.bounds_min.z()) + ", " + metres(q.bounds_max.z()) + "]";
  if (low < q.bounds_min.z()) fail("min_depth", metres(low) + " is above" + z_range);
  if (high > q.bounds_max.z()) fail("max_depth", metres(high) + " is below" + z_range);
  if (goal.z() < low) {
    fail("goal",
         "depth " + metres(goal.z()) + " is above the band (min_depth " + metres(low) + ")");
  }
  if (goal.z() > high) {
    fail("goal",
         "depth " + metres(goal.z()) + " is below the band (max_depth " + metres(high) + ")");
  }
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
  if (!(q.min_altitude >= 0.0) || !std::isfinite(q.min_altitude)) {
    fail("min_altitude", "must be >= 0 m (0 = none)");
  }
  checkBand(q, goal, fail);
}

MissionPlan parseMission(const std::string& yaml_text, const std::string& source) {
  return asMissionError([&] { return readMission(config::loadYamlText(yaml_text, source)); });
}

MissionPlan loadMissionFile(const std::string& path) {
  return asMissionError([&] { return readMission(config::loadYamlFile(path)); });
}

std::string toYaml(const MissionPlan& plan) {
  std::ostringstream out;
  out << "mission:\n  name: " << quoted(plan.name) << "\n  queries:\n";
  for (const MissionQuery& q : plan.queries) {
    out << "    - name: " << quoted(q.name) << "\n"
        << "      goal: " << vectorYaml(q.goal) << "\n"
        << "      goal_tolerance: " << number(q.goal_tolerance) << "\n"
        << "      time_budget: " << number(q.time_budget) << "\n"
        << "      objective: " << (q.visibility_objective ? "visibility" : "path_length") << "\n"
        << "      expected_distance: " << number(q.expected_distance) << "\n"
        << "      admissible_range: " << number(q.admissible_range) << "\n"
        << "      bounds: {min: " << vectorYaml(q.bounds_min)
        << ", max: " << vectorYaml(q.bounds_max) << "}\n"
        << "      fixed_depth: " << (q.fixed_depth ? "true" : "false") << "\n";
    if (q.depth) out << "      depth: " << number(*q.depth) << "\n";
    if (q.min_depth) out << "      min_depth: " << number(*q.min_depth) << "\n";
    if (q.max_depth) out << "      max_depth: " << number(*q.max_depth) << "\n";
    if (q.min_altitude != 0.0) out << "      min_altitude: " << number(q.min_altitude) << "\n";
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
  // On the wire no band is both ends 0 (planning.idl).
  query.min_depth(q.min_depth.value_or(0.0));
  query.max_depth(q.max_depth.value_or(0.0));
  query.min_altitude(q.min_altitude);
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
  if (query.min_depth() != 0.0 || query.max_depth() != 0.0) {
    q.min_depth = query.min_depth();  // checkQuery refuses an inverted one
    q.max_depth = query.max_depth();
  }
  q.min_altitude = query.min_altitude();
  return q;
}

}  // namespace auv::mission
