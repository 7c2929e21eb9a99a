// The mission file: defaults and per-query overrides, the round trip through toYaml, one
// MissionError naming the field for each kind of malformed input, and the PlannerQuery
// conversion both ways.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>

#include "auv/mission/mission_plan.h"

namespace auv::mission {
namespace {

const char* const kValidMission = R"(mission:
  name: breakwater
  defaults:
    goal_tolerance: 2.0
    objective: path_length
    bounds: {min: [-10, -20, 0], max: [60, 20, 30]}
    fixed_depth: true
    depth: 8.5
  queries:
    - name: across
      goal: [50, 0, 8.5]
    - goal: [5, 15, 12]
      goal_tolerance: 0.75
      time_budget: 3.5
      objective: visibility
      expected_distance: 4.0
      admissible_range: 2.0
      fixed_depth: false
      bounds: {min: [0, 0, 2], max: [10, 18, 20]}
)";

/// The MissionError message of parsing `text`, or "" when it parsed.
std::string errorOf(const std::string& text) {
  try {
    parseMission(text, "test.yaml");
  } catch (const MissionError& error) {
    return error.what();
  }
  return "";
}

/// A valid one-query mission with `query_fields` (YAML lines of the query, 6-space indent).
std::string oneQuery(const std::string& query_fields) {
  return "mission:\n  queries:\n    - goal: [5, 5, 5]\n      bounds: {min: [0, 0, 0], max: [10, "
         "10, 10]}\n" +
         query_fields;
}

#define EXPECT_CONTAINS(text, part) \
  EXPECT_NE(std::string(text).find(part), std::string::npos) << "'" << (text) << "'"

void expectSameQuery(const MissionQuery& a, const MissionQuery& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.goal, b.goal);
  EXPECT_EQ(a.goal_tolerance, b.goal_tolerance);
  EXPECT_EQ(a.time_budget, b.time_budget);
  EXPECT_EQ(a.visibility_objective, b.visibility_objective);
  EXPECT_EQ(a.expected_distance, b.expected_distance);
  EXPECT_EQ(a.admissible_range, b.admissible_range);
  EXPECT_EQ(a.bounds_min, b.bounds_min);
  EXPECT_EQ(a.bounds_max, b.bounds_max);
  EXPECT_EQ(a.fixed_depth, b.fixed_depth);
  EXPECT_EQ(a.depth, b.depth);
  EXPECT_EQ(a.min_depth, b.min_depth);
  EXPECT_EQ(a.max_depth, b.max_depth);
  EXPECT_EQ(a.min_altitude, b.min_altitude);
}

TEST(MissionPlanTest, DefaultsApplyAndQueriesOverrideThem) {
  const MissionPlan plan = parseMission(kValidMission, "test.yaml");
  EXPECT_EQ(plan.name, "breakwater");
  ASSERT_EQ(plan.queries.size(), 2u);

  const MissionQuery& first = plan.queries[0];  // everything from the defaults
  EXPECT_EQ(first.name, "across");
  EXPECT_EQ(first.goal, Eigen::Vector3d(50, 0, 8.5));
  EXPECT_EQ(first.goal_tolerance, 2.0);
  EXPECT_EQ(first.time_budget, 0.0);  // built-in default
  EXPECT_FALSE(first.visibility_objective);
  EXPECT_EQ(first.bounds_min, Eigen::Vector3d(-10, -20, 0));
  EXPECT_EQ(first.bounds_max, Eigen::Vector3d(60, 20, 30));
  EXPECT_TRUE(first.fixed_depth);
  ASSERT_TRUE(first.depth.has_value());
  EXPECT_EQ(*first.depth, 8.5);

  const MissionQuery& second = plan.queries[1];  // its own values win
  EXPECT_EQ(second.name, "query 2");             // unnamed: numbered from 1
  EXPECT_EQ(second.goal, Eigen::Vector3d(5, 15, 12));
  EXPECT_EQ(second.goal_tolerance, 0.75);
  EXPECT_EQ(second.time_budget, 3.5);
  EXPECT_TRUE(second.visibility_objective);
  EXPECT_EQ(second.expected_distance, 4.0);
  EXPECT_EQ(second.admissible_range, 2.0);
  EXPECT_FALSE(second.fixed_depth);
  EXPECT_EQ(second.bounds_min, Eigen::Vector3d(0, 0, 2));
  EXPECT_EQ(second.bounds_max, Eigen::Vector3d(10, 18, 20));
  ASSERT_TRUE(second.depth.has_value());  // from the defaults; unused without fixed_depth
  EXPECT_EQ(*second.depth, 8.5);
}

TEST(MissionPlanTest, RoundTripsThroughToYaml) {
  MissionPlan plan = parseMission(kValidMission, "test.yaml");
  plan.queries[1].depth.reset();  // an unset depth must stay unset
  plan.queries[0].goal = {50.125, -0.1, 8.5};
  const std::string yaml = toYaml(plan);
  const MissionPlan again = parseMission(yaml, "round trip");
  EXPECT_EQ(again.name, plan.name);
  ASSERT_EQ(again.queries.size(), plan.queries.size()) << yaml;
  for (std::size_t i = 0; i < plan.queries.size(); ++i) {
    SCOPED_TRACE("query " + std::to_string(i));
    expectSameQuery(again.queries[i], plan.queries[i]);
  }
}

TEST(MissionPlanTest, RoundTripsEveryDigit) {
  // toYaml wrote 10 significant digits: bounds 1e-11 m apart were written equal, a mission the
  // handler accepted and then refused to resume from its progress.yaml.
  const MissionPlan plan = parseMission(
      "mission:\n  queries:\n    - {goal: [1.00000000001, 0.5, 0.5], bounds: {min: "
      "[1.00000000001, 0, 0], max: [1.00000000002, 1, 1]}, goal_tolerance: 0.1234567890123, "
      "depth: 0.30000000000000004, time_budget: 1e-7, min_altitude: -0.0}\n",
      "thin.yaml");
  const std::string yaml = toYaml(plan);
  const MissionPlan again = parseMission(yaml, "round trip");
  ASSERT_EQ(again.queries.size(), 1u);
  expectSameQuery(again.queries[0], plan.queries[0]);
  EXPECT_EQ(toYaml(again), yaml);
  EXPECT_NE(yaml.find("max: [1.00000000002, 1, 1]"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("time_budget: 1e-07\n"), std::string::npos) << yaml;  // shortest text
}

TEST(MissionPlanTest, NamesWithYamlSyntaxRoundTrip) {
  // Mission ids come from operators (StartMissionRequest.mission_id) and end up in the log's
  // mission.yaml: whatever they contain must read back as written.
  for (const std::string name :
       {"dock #2", "a: b", "say \"hi\"", "[x]", "back\\slash", "- dash", "true", "'q'"}) {
    SCOPED_TRACE(name);
    MissionPlan plan;
    plan.name = name;
    MissionQuery query;
    query.name = name;
    query.goal = {1, 1, 1};
    query.bounds_max = {5, 5, 5};
    plan.queries = {query};
    try {
      const MissionPlan again = parseMission(toYaml(plan), "round trip");
      EXPECT_EQ(again.name, name);
      ASSERT_EQ(again.queries.size(), 1u);
      EXPECT_EQ(again.queries[0].name, name);
    } catch (const MissionError& error) {
      ADD_FAILURE() << error.what() << "\n" << toYaml(plan);
    }
  }
}

TEST(MissionPlanTest, LoadsAFileAndNamesAMissingOne) {
  const std::string path = ::testing::TempDir() + "mission_plan_test.yaml";
  std::ofstream(path) << kValidMission;
  EXPECT_EQ(loadMissionFile(path).queries.size(), 2u);
  const std::string missing = ::testing::TempDir() + "no_such_mission.yaml";
  try {
    loadMissionFile(missing);
    FAIL() << "loaded a missing file";
  } catch (const MissionError& error) {
    EXPECT_CONTAINS(error.what(), missing);
  }
}

TEST(MissionPlanTest, MalformedYamlNamesTheLine) {
  const std::string error =
      errorOf("mission:\n  name: m\n  queries:\n    - goal: [1, 2, 3]\n   bad_indent: x\n");
  EXPECT_CONTAINS(error, "test.yaml");
  EXPECT_CONTAINS(error, "test.yaml:5:");  // file:line:column, as every reader
  EXPECT_CONTAINS(error, "malformed YAML");
}

TEST(MissionPlanTest, MissingMissionSection) {
  const std::string error = errorOf("queries:\n  - goal: [1, 2, 3]\n");
  EXPECT_CONTAINS(error, "test.yaml");
  EXPECT_CONTAINS(error, "'mission:'");
}

TEST(MissionPlanTest, UnknownFieldListsTheKnownOnes) {
  const std::string error = errorOf(oneQuery("      goal_tol: 2\n"));
  EXPECT_CONTAINS(error, "queries[0]");
  EXPECT_CONTAINS(error, "queries[0].goal_tol: unknown setting");
  EXPECT_CONTAINS(error, "known:");
  EXPECT_CONTAINS(error, "goal_tolerance");
  EXPECT_CONTAINS(error, "admissible_range");

  const std::string top = errorOf("mission:\n  querys: []\n");
  EXPECT_CONTAINS(top, "test.yaml: mission.querys: unknown setting");
  EXPECT_CONTAINS(top, "queries");
}

TEST(MissionPlanTest, UnknownFieldSuggestsTheClosestOne) {
  const std::string error = errorOf(oneQuery("      goal_tolerence: 2\n"));
  EXPECT_CONTAINS(error, "test.yaml: mission.queries[0].goal_tolerence: unknown setting");
  EXPECT_CONTAINS(error, "did you mean 'goal_tolerance'?");
  EXPECT_CONTAINS(error, "known: name, goal, goal_tolerance");
  EXPECT_CONTAINS(errorOf("mission:\n  defults: {}\n  queries: []\n"), "did you mean 'defaults'?");
}

TEST(MissionPlanTest, ScalarsFollowYaml12) {
  // YAML 1.1 booleans are not booleans (the rule of every reader: auv/config/yaml_scalars.h).
  for (const std::string word : {"yes", "no", "on", "off", "y", "1"}) {
    SCOPED_TRACE(word);
    const std::string error = errorOf(oneQuery("      fixed_depth: " + word + "\n"));
    EXPECT_CONTAINS(error, "test.yaml: mission.queries[0].fixed_depth");
    EXPECT_CONTAINS(error, "expected a boolean (true or false), got '" + word + "'");
  }
  EXPECT_CONTAINS(errorOf(oneQuery("      goal_tolerance: \"2\"\n")), "(a quoted string)");
  EXPECT_CONTAINS(errorOf(oneQuery("      time_budget: 1_000\n")), "got '1_000'");
  EXPECT_CONTAINS(errorOf(oneQuery("      time_budget: .inf\n")), "expected a finite number");
  const MissionPlan plan =
      parseMission(oneQuery("      fixed_depth: True\n      time_budget: 0x10\n"), "test.yaml");
  EXPECT_TRUE(plan.queries[0].fixed_depth);
  EXPECT_EQ(plan.queries[0].time_budget, 16.0);  // YAML 1.2 hex integer
}

TEST(MissionPlanTest, GoalMustBeNorthEastDown) {
  const std::string two = errorOf("mission:\n  queries:\n    - goal: [1, 2]\n");
  EXPECT_CONTAINS(two, "queries[0].goal");
  EXPECT_CONTAINS(two, "[north, east, down]");
  const std::string text = errorOf("mission:\n  queries:\n    - goal: [1, two, 3]\n");
  EXPECT_CONTAINS(text, "queries[0].goal[1]");
  EXPECT_CONTAINS(text, "expected a finite number, got 'two'");
  const std::string none = errorOf("mission:\n  queries:\n    - name: a\n");
  EXPECT_CONTAINS(none, "queries[0]");
  EXPECT_CONTAINS(none, "no goal");
}

TEST(MissionPlanTest, GoalOutsideTheBounds) {
  const std::string error = errorOf(
      "mission:\n  queries:\n    - name: far\n      goal: [5, 12, 5]\n"
      "      bounds: {min: [0, 0, 0], max: [10, 10, 10]}\n");
  EXPECT_CONTAINS(error, "query 'far' goal");
  EXPECT_CONTAINS(error, "outside the bounds");
  EXPECT_CONTAINS(error, "[5, 12, 5]");
}

TEST(MissionPlanTest, BoundsMinMustBeBelowMax) {
  const std::string equal = errorOf(
      "mission:\n  queries:\n    - goal: [5, 5, 5]\n"
      "      bounds: {min: [0, 5, 0], max: [10, 5, 10]}\n");
  EXPECT_CONTAINS(equal, "bounds");
  EXPECT_CONTAINS(equal, "max must exceed min");
  EXPECT_CONTAINS(equal, "axis 1");
  const std::string inverted = errorOf(
      "mission:\n  queries:\n    - goal: [5, 5, 5]\n"
      "      bounds: {min: [10, 0, 0], max: [0, 10, 10]}\n");
  EXPECT_CONTAINS(inverted, "axis 0");
  const std::string shape =
      errorOf("mission:\n  queries:\n    - goal: [5, 5, 5]\n      bounds: [0, 10]\n");
  EXPECT_CONTAINS(shape, "queries[0].bounds");
  EXPECT_CONTAINS(shape, "{min: [n, e, d], max: [n, e, d]}");
}

TEST(MissionPlanTest, NegativeGoalTolerance) {
  const std::string error = errorOf(oneQuery("      goal_tolerance: -1\n"));
  EXPECT_CONTAINS(error, "goal_tolerance");
  EXPECT_CONTAINS(error, "must be > 0");
  EXPECT_CONTAINS(errorOf(oneQuery("      goal_tolerance: 0\n")), "goal_tolerance");
}

TEST(MissionPlanTest, ObjectiveMustBeKnown) {
  const std::string error = errorOf(oneQuery("      objective: shortest\n"));
  EXPECT_CONTAINS(error, "queries[0].objective");
  EXPECT_CONTAINS(error, "'shortest'");
  EXPECT_CONTAINS(error, "visibility, path_length");
}

TEST(MissionPlanTest, EmptyQueries) {
  EXPECT_CONTAINS(errorOf("mission:\n  name: m\n  queries: []\n"), "mission.queries");
  EXPECT_CONTAINS(errorOf("mission:\n  name: m\n"), "expected a non-empty list");
}

TEST(MissionPlanTest, OtherFieldsAreCheckedToo) {
  EXPECT_CONTAINS(errorOf(oneQuery("      time_budget: -2\n")), "time_budget");
  EXPECT_CONTAINS(errorOf(oneQuery("      expected_distance: -1\n")), "expected_distance");
  EXPECT_CONTAINS(errorOf(oneQuery("      fixed_depth: maybe\n")),
                  "expected a boolean (true or false), got 'maybe'");
  EXPECT_CONTAINS(errorOf(oneQuery("      fixed_depth: true\n      depth: -3\n")), "depth");
  EXPECT_CONTAINS(errorOf("mission:\n  queries:\n    - goal: [5, 5, -1]\n"
                          "      bounds: {min: [0, 0, -5], max: [10, 10, 10]}\n"),
                  "above the surface");
}

TEST(MissionPlanTest, FixedDepthAcceptsFlatDepthBounds) {
  const std::string flat =
      "mission:\n  queries:\n    - goal: [5, 5, 0]\n"
      "      bounds: {min: [0, 0, 6], max: [10, 10, 6]}\n";
  // Flat z bounds are an empty region in 3D...
  EXPECT_CONTAINS(errorOf(flat), "axis 2");
  // ...and just the plane for a fixed-depth query, whose goal z is not checked against them.
  const MissionPlan plan = parseMission(flat + "      fixed_depth: true\n", "flat.yaml");
  ASSERT_EQ(plan.queries.size(), 1u);
  EXPECT_TRUE(plan.queries[0].fixed_depth);
  EXPECT_FALSE(plan.queries[0].depth.has_value());
  EXPECT_NO_THROW(parseMission(flat + "      fixed_depth: true\n      depth: 6\n", "flat.yaml"));
}

TEST(MissionPlanTest, PlannerQueryKeepsEveryField) {
  const MissionPlan plan = parseMission(kValidMission, "test.yaml");
  MissionQuery query = plan.queries[1];
  query.name = "query 4";  // fromPlannerQuery names by index
  query.fixed_depth = true;
  query.depth = 7.25;

  const msg::PlannerQuery wire = toPlannerQuery(query);
  EXPECT_EQ(wire.goal().position().x(), 5);
  EXPECT_EQ(wire.goal().position().y(), 15);
  EXPECT_EQ(wire.goal().position().z(), 12);
  EXPECT_EQ(wire.goal_tolerance(), 0.75);
  EXPECT_EQ(wire.time_budget(), 3.5);
  EXPECT_EQ(wire.objective(), msg::PLANNER_OBJECTIVE_VISIBILITY_COST);
  EXPECT_EQ(wire.expected_distance(), 4.0);
  EXPECT_EQ(wire.admissible_range(), 2.0);
  EXPECT_EQ(wire.bounds_min().z(), 2);
  EXPECT_EQ(wire.bounds_max().y(), 18);
  EXPECT_TRUE(wire.fixed_depth());
  EXPECT_EQ(wire.depth(), 7.25);
  EXPECT_EQ(wire.header().frame_id(), "world");
  expectSameQuery(fromPlannerQuery(wire, 3), query);

  // An unset depth travels as NaN and comes back unset; the other objective survives too.
  query.depth.reset();
  query.visibility_objective = false;
  const msg::PlannerQuery unset = toPlannerQuery(query);
  EXPECT_TRUE(std::isnan(unset.depth()));
  EXPECT_EQ(unset.objective(), msg::PLANNER_OBJECTIVE_PATH_LENGTH);
  expectSameQuery(fromPlannerQuery(unset, 3), query);
}

}  // namespace
}  // namespace auv::mission

namespace auv::mission {
namespace {

/// A 3-D mission: the band and min_altitude in the defaults, one query overriding them.
const char* const kBandMission = R"(mission:
  defaults:
    bounds: {min: [0, 0, 0], max: [40, 20, 20]}
    fixed_depth: false
    min_depth: 2.0
    max_depth: 12.0
    min_altitude: 1.5
  queries:
    - goal: [30, 10, 6]
    - goal: [5, 5, 15]
      max_depth: 18
      min_altitude: 0
)";

TEST(MissionBandTest, BandAndMinAltitudeComeFromDefaultsAndQueries) {
  MissionPlan plan = parseMission(kBandMission, "band.yaml");
  ASSERT_EQ(plan.queries.size(), 2u);
  EXPECT_EQ(plan.queries[0].min_depth, 2.0);
  EXPECT_EQ(plan.queries[0].max_depth, 12.0);
  EXPECT_EQ(plan.queries[0].min_altitude, 1.5);
  EXPECT_EQ(plan.queries[1].min_depth, 2.0);
  EXPECT_EQ(plan.queries[1].max_depth, 18.0);
  EXPECT_EQ(plan.queries[1].min_altitude, 0.0);
  // Through toYaml and back, and through the PlannerQuery and back.
  const MissionPlan again = parseMission(toYaml(plan), "round trip");
  ASSERT_EQ(again.queries.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    SCOPED_TRACE("query " + std::to_string(i));
    expectSameQuery(again.queries[i], plan.queries[i]);
    plan.queries[i].name = "query " + std::to_string(i + 1);
    const msg::PlannerQuery wire = toPlannerQuery(plan.queries[i]);
    EXPECT_EQ(wire.min_depth(), 2.0);
    EXPECT_EQ(wire.max_depth(), i == 0 ? 12.0 : 18.0);
    EXPECT_EQ(wire.min_altitude(), i == 0 ? 1.5 : 0.0);
    expectSameQuery(fromPlannerQuery(wire, i), plan.queries[i]);
  }
  // No band: both ends 0 on the wire, and unset again on the way back.
  MissionQuery plain = plan.queries[0];
  plain.min_depth.reset();
  plain.max_depth.reset();
  const msg::PlannerQuery wire = toPlannerQuery(plain);
  EXPECT_EQ(wire.min_depth(), 0.0);
  EXPECT_EQ(wire.max_depth(), 0.0);
  EXPECT_FALSE(fromPlannerQuery(wire, 0).min_depth.has_value());
}

TEST(MissionBandTest, BadBandsAreRefusedNamingTheField) {
  const std::string base =
      "mission:\n  queries:\n    - name: dive\n      goal: [5, 5, 5]\n"
      "      bounds: {min: [0, 0, 1], max: [10, 10, 10]}\n";
  const auto band = [&](const std::string& fields) { return errorOf(base + fields); };
  EXPECT_EQ(band("      min_depth: 2\n      max_depth: 8\n      min_altitude: 1\n"), "");
  EXPECT_CONTAINS(band("      min_depth: 6\n      max_depth: 6\n"),
                  "test.yaml: query 'dive' min_depth: 6 m must be shallower than max_depth 6 m");
  EXPECT_CONTAINS(band("      min_depth: 7\n      max_depth: 3\n"), "min_depth: 7 m must be");
  EXPECT_CONTAINS(band("      min_depth: 0.5\n      max_depth: 8\n"),
                  "query 'dive' min_depth: 0.5 m is above the bounds' z-range [1 m, 10 m]");
  EXPECT_CONTAINS(band("      min_depth: 2\n      max_depth: 11\n"),
                  "query 'dive' max_depth: 11 m is below the bounds' z-range [1 m, 10 m]");
  EXPECT_CONTAINS(band("      min_depth: 2\n"), "query 'dive' min_depth: given without max_depth");
  EXPECT_CONTAINS(band("      max_depth: 8\n"), "query 'dive' max_depth: given without min_depth");
  EXPECT_CONTAINS(band("      min_depth: -1\n      max_depth: 8\n"), "min_depth: must be >= 0");
  EXPECT_CONTAINS(band("      min_altitude: -0.5\n"), "query 'dive' min_altitude: must be >= 0");
  EXPECT_CONTAINS(band("      min_depth: 2\n      max_depth: 8\n      fixed_depth: true\n"),
                  "query 'dive' min_depth: a depth band is for 3-D planning");
  // The goal must be inside the band: above it or below it is refused before anything moves.
  EXPECT_CONTAINS(band("      min_depth: 6\n      max_depth: 9\n"),
                  "query 'dive' goal: depth 5 m is above the band (min_depth 6 m)");
  EXPECT_CONTAINS(band("      min_depth: 2\n      max_depth: 4\n"),
                  "query 'dive' goal: depth 5 m is below the band (max_depth 4 m)");
  EXPECT_CONTAINS(band("      min_depth: [2]\n      max_depth: 4\n"), "min_depth");
  // min_altitude alone is fine in 2-D too: the planner keeps it over known seabed.
  EXPECT_EQ(band("      fixed_depth: true\n      min_altitude: 2\n"), "");
}

}  // namespace
}  // namespace auv::mission
