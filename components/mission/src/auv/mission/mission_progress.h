#pragma once
// A mission's progress, persisted by the mission handler after every change so that a handler
// restarted within the same launch resumes the mission instead of losing it or starting over
// (docs/reliability.md). The file, `<log_dir>/progress.yaml`, is replaced whole on each write
// (auv/config/state_file.h); its format is in components/mission/README.md.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "auv/mission/mission_plan.h"
#include "auv/msg/all.h"

namespace auv::mission {

struct MissionProgress {
  std::string launch_id;  ///< AUV_LAUNCH_ID of the launch that ran the mission
  std::string mission_id;
  MissionPlan plan;
  msg::MissionState state = msg::MISSION_STATE_IDLE;
  int32_t query_index = -1;  ///< the query in progress (-1: none)
  double start_time = 0.0;   ///< s, node clock
  uint32_t queries_succeeded = 0;
  uint32_t queries_failed = 0;
  uint32_t waypoints_received = 0;
  uint32_t waypoints_reached = 0;
  uint32_t waypoints_cancelled = 0;
  uint32_t recoveries = 0;        ///< over the whole mission
  uint32_t query_recoveries = 0;  ///< of the query in progress (max_recoveries counts these)
  /// Ids the handler hands out next: a resumed mission never reuses one the planner or the
  /// controller has seen.
  uint64_t next_query_id = 1;
  uint64_t next_command_id = 1;
  /// m, the plane of fixed-depth queries that give no depth, once the first one set it.
  std::optional<double> mission_depth;

  /// Whether the mission was still going on (a state the handler resumes).
  bool running() const;
};

/// The progress as YAML (what parseProgress reads back).
std::string toYaml(const MissionProgress& progress);
/// Parses progress YAML; throws MissionError naming `source` and the field.
MissionProgress parseProgress(const std::string& yaml_text, const std::string& source);
/// Reads `file`: nothing when it does not exist; MissionError naming it when unreadable.
std::optional<MissionProgress> readProgress(const std::filesystem::path& file);
/// Replaces `file` atomically; throws std::runtime_error naming it.
void writeProgress(const std::filesystem::path& file, const MissionProgress& progress);

/// Whether a mission in `state` is still going on (what the handler resumes).
bool isRunning(msg::MissionState state);

/// MissionState from its name (toString's); nothing for an unknown name.
std::optional<msg::MissionState> missionStateFromString(const std::string& name);

}  // namespace auv::mission
