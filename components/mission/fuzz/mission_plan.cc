// Fuzz harness: mission files as `auv mission start FILE` and the mission handler read them
// (parseMission: the shared strict YAML reader, then checkQuery on every query). A mission that
// is accepted must survive the handler's own round trip (toYaml, as written into progress.yaml
// and mission.yaml, read back to the same plan). A clear error is a MissionError naming the file,
// the query and the field; anything else (a crash, a sanitizer report, another exception, a
// written plan that does not read back) is a bug.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "auv/mission/mission_plan.h"

using auv::mission::MissionError;
using auv::mission::MissionPlan;
using auv::mission::MissionQuery;
using auv::mission::parseMission;
using auv::mission::toYaml;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  MissionPlan plan;
  try {
    plan = parseMission(input, "fuzz_mission.yaml");
  } catch (const MissionError&) {
    return 0;
  }
  const std::string written = toYaml(plan);
  try {
    const std::string rewritten = toYaml(parseMission(written, "written mission.yaml"));
    if (rewritten != written) {
      std::fprintf(stderr, "mission changed in a round trip:\n%s---\n%s", written.c_str(),
                   rewritten.c_str());
      std::abort();
    }
  } catch (const MissionError& e) {
    std::fprintf(stderr, "a written mission does not read back: %s\n%s", e.what(), written.c_str());
    std::abort();
  }
  return 0;
}

/// The two mission files of components/mission/README.md, and every field written by toYaml.
std::vector<std::string> auvFuzzSeeds() {
  const std::string fixed_depth = R"(mission:
  name: canyon                 # mission id prefix
  defaults:                    # optional: every query starts from these
    objective: visibility      # visibility (Eq. 1 + length) | path_length
    expected_distance: 1.5     # m, d_e of Eq. (1)
    admissible_range: 1.0      # m, Δd_a of Eq. (1)
    fixed_depth: true          # plan in the horizontal plane (the paper's 2-D profiler)
    depth: 3.0                 # m, the plane; unset = the vehicle's depth when the mission's
                               # first query starts (kept for the others)
    bounds: {min: [-40, -20, 0], max: [40, 30, 8.5]}   # m NED, the sampling region
    goal_tolerance: 1.5        # m, ε_goal
    time_budget: 0             # s to the first waypoint; 0 = the planner's default
  queries:                     # run in order; each starts where the vehicle is
    - {name: traverse, goal: [29.5, 1.1, 3.0]}
    - {name: back, goal: [-20.5, 19.9, 3.0], goal_tolerance: 2.0}
)";
  const std::string band = R"(mission:
  name: boulders
  defaults:
    fixed_depth: false         # plan in 3-D: the planner samples depth too
    bounds: {min: [-40, -30, 0], max: [40, 30, 20]}
    min_depth: 2.0             # m, the band: every waypoint at 2 m <= depth <= 9 m; both or
    max_depth: 9.0             # neither (unset: the bounds' z-range), inside the bounds' z-range
    min_altitude: 1.0          # m, water kept between the planner's clearance sphere and known
                               # seabed below (0 = none); needs a map of the seabed to act on
  queries:
    - {name: over, goal: [30, 0, 4.0]}                # the goal lies inside the band
    - {name: low, goal: [-20, 10, 8.0], max_depth: 12}  # a query overrides any field
)";
  MissionPlan plan;
  plan.name = "survey: \"north\" # wall";
  MissionQuery q;
  q.name = "leg 1";
  q.goal = {12.5, -3.25, 4.0};
  q.bounds_min = {-10, -10, 0};
  q.bounds_max = {20, 10, 15};
  q.time_budget = 2.5;
  q.visibility_objective = false;
  q.min_depth = 1.0;
  q.max_depth = 9.5;
  q.min_altitude = 0.5;
  plan.queries.push_back(q);
  q = MissionQuery();
  q.name = "leg 2";
  q.goal = {0, 0, 3};
  q.bounds_min = {-10, -10, 3};
  q.bounds_max = {20, 10, 3};
  q.fixed_depth = true;
  q.depth = 3.0;
  plan.queries.push_back(q);
  return {fixed_depth, band, toYaml(parseMission(fixed_depth, "canyon.yaml")),
          toYaml(parseMission(band, "boulders.yaml")), toYaml(plan)};
}
