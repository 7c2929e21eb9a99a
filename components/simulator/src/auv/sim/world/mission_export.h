#pragma once
// The scenario's queries as a mission file for the mission handler (format:
// components/mission/README.md), so a simulated world comes with its inspection mission.

#include <string>

#include "auv/sim/world/mesh.h"
#include "auv/sim/world/scenario.h"

namespace auv::sim {

struct MissionExportOptions {
  double bounds_margin = 4.0;      ///< m, the sampling region: mesh, start and goals grown by this
  double expected_distance = 1.5;  ///< m, d_e of Eq. (1): beyond the planner clearance (1.2 m)
  double admissible_range = 1.0;   ///< m, Δd_a of Eq. (1)
  std::string objective = "visibility";  ///< visibility (Eq. 1 + length) or path_length
};

/// Mission YAML: one query per scenario query, horizontal bounds from the world mesh (in the
/// world frame), the start and the goals, depth range from the surface to the seabed. The
/// scenario's `mission:` section decides the mode: fixed depth at the scenario's start depth
/// (the default), or 3-D planning with its depth band and minimum altitude.
std::string missionYaml(const Scenario& scenario, const Mesh& world_mesh,
                        const MissionExportOptions& options = {});

/// Writes `yaml` to `path` through a temporary file and a rename: `auv mission start --wait`
/// polls for the file and must never read it half-written. Throws std::runtime_error naming
/// the file when it cannot be written.
void writeMissionFile(const std::string& path, const std::string& yaml);

}  // namespace auv::sim
