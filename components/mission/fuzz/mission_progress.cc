// Fuzz harness: the mission handler's progress file, `<log_dir>/progress.yaml`, as a restarted
// handler reads it to resume (parseProgress, with the mission plan it holds). A progress that is
// accepted must survive the handler's own round trip (toYaml, as writeProgress writes it, read
// back to the same progress). A clear error is a MissionError naming the file and the field;
// anything else (a crash, a sanitizer report, another exception, a written progress that does
// not read back) is a bug.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "auv/mission/mission_progress.h"

using auv::mission::MissionError;
using auv::mission::MissionProgress;
using auv::mission::parseMission;
using auv::mission::parseProgress;
using auv::mission::toYaml;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  MissionProgress progress;
  try {
    progress = parseProgress(input, "fuzz_progress.yaml");
  } catch (const MissionError&) {
    return 0;
  }
  const std::string written = toYaml(progress);
  try {
    const std::string rewritten = toYaml(parseProgress(written, "written progress.yaml"));
    if (rewritten != written) {
      std::fprintf(stderr, "progress changed in a round trip:\n%s---\n%s", written.c_str(),
                   rewritten.c_str());
      std::abort();
    }
  } catch (const MissionError& e) {
    std::fprintf(stderr, "a written progress does not read back: %s\n%s", e.what(),
                 written.c_str());
    std::abort();
  }
  return 0;
}

/// Progress files as the handler writes them (toYaml) in every state, with and without a
/// mission depth, of the fixed-depth mission of components/mission/README.md.
std::vector<std::string> auvFuzzSeeds() {
  const std::string mission = R"(mission:
  name: canyon
  defaults:
    fixed_depth: true
    bounds: {min: [-40, -20, 0], max: [40, 30, 8.5]}
  queries:
    - {name: traverse, goal: [29.5, 1.1, 3.0]}
    - {name: back, goal: [-20.5, 19.9, 3.0], goal_tolerance: 2.0}
)";
  std::vector<std::string> seeds;
  MissionProgress p;
  p.launch_id = "20261129-101500-4242";
  p.mission_id = "canyon-1";
  p.plan = parseMission(mission, "canyon.yaml");
  p.start_time = 1234.5;
  p.next_query_id = 3;
  p.next_command_id = 17;
  for (auv::msg::MissionState state :
       {auv::msg::MISSION_STATE_IDLE, auv::msg::MISSION_STATE_CHECKING_READINESS,
        auv::msg::MISSION_STATE_WAITING_FOR_WAYPOINT, auv::msg::MISSION_STATE_EXECUTING,
        auv::msg::MISSION_STATE_SUCCEEDED, auv::msg::MISSION_STATE_FAILED,
        auv::msg::MISSION_STATE_ABORTED, auv::msg::MISSION_STATE_RECOVERING}) {
    p.state = state;
    p.query_index = p.running() ? 1 : -1;
    seeds.push_back(toYaml(p));
  }
  p.state = auv::msg::MISSION_STATE_RECOVERING;
  p.query_index = 0;
  p.queries_succeeded = 1;
  p.waypoints_received = 12;
  p.waypoints_reached = 10;
  p.waypoints_cancelled = 2;
  p.recoveries = 3;
  p.query_recoveries = 1;
  p.mission_depth = 3.0;
  seeds.push_back(toYaml(p));
  return seeds;
}
