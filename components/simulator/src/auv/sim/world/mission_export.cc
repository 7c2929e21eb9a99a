#include "auv/sim/world/mission_export.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <Eigen/Geometry>

namespace auv::sim {

std::string missionYaml(const Scenario& scenario, const Mesh& world_mesh,
                        const MissionExportOptions& options) {
  Eigen::AlignedBox2d horizontal;
  for (const Eigen::Vector3f& v : world_mesh.vertices)
    horizontal.extend(v.head<2>().cast<double>());
  horizontal.extend(scenario.start_position.head<2>());
  for (const MissionQuery& q : scenario.queries) horizontal.extend(q.goal.head<2>());
  const Eigen::Vector2d lo = horizontal.min().array() - options.bounds_margin;
  const Eigen::Vector2d hi = horizontal.max().array() + options.bounds_margin;
  std::ostringstream out;
  out.precision(6);
  out << std::fixed;
  out << "# Inspection mission of scenario '" << scenario.name << "' (" << scenario.file
      << "),\n# written by the simulator: `auv mission start <this file>`.\n"
      << "mission:\n  name: " << scenario.name << "\n  defaults:\n"
      << "    objective: " << options.objective << "\n"
      << "    expected_distance: " << options.expected_distance << "\n"
      << "    admissible_range: " << options.admissible_range << "\n"
      << "    # fixed_depth: true plans in one horizontal plane at `depth` (the paper's 2-D mode,\n"
      << "    # profiling sonar; worlds of vertical walls). false plans in 3-D inside\n"
      << "    # [min_depth, max_depth], min_altitude above known seabed (natural terrain: "
         "boulders,\n"
      << "    # arches, overhangs; needs 3-D sensing such as a multibeam).\n";
  const MissionPlanning& planning = scenario.mission;
  if (planning.fixed_depth) {
    // The plane of the scenario's start, not the vehicle's depth at the moment the mission
    // starts: an idle, positively buoyant vehicle may have floated up by then.
    out << "    fixed_depth: true\n"
        << "    depth: " << scenario.start_position.z() << "\n";
  } else {
    out << "    fixed_depth: false\n";
    if (planning.hasBand())
      out << "    min_depth: " << planning.min_depth << "\n"
          << "    max_depth: " << planning.max_depth << "\n";
  }
  if (planning.min_altitude > 0.0) out << "    min_altitude: " << planning.min_altitude << "\n";
  out << "    bounds: {min: [" << lo.x() << ", " << lo.y() << ", 0.0], max: [" << hi.x() << ", "
      << hi.y() << ", " << scenario.seabed_depth << "]}\n"
      << "  queries:\n";
  for (const MissionQuery& q : scenario.queries) {
    out << "    - {name: " << q.name << ", goal: [" << q.goal.x() << ", " << q.goal.y() << ", "
        << q.goal.z() << "], goal_tolerance: " << q.tolerance << "}\n";
  }
  return out.str();
}

void writeMissionFile(const std::string& path, const std::string& yaml) {
  const std::string partial = path + ".part";
  {
    std::ofstream out(partial);
    out << yaml;
    if (!out.flush()) throw std::runtime_error(partial + ": cannot write the mission file");
  }
  std::error_code error;
  std::filesystem::rename(partial, path, error);
  if (error) throw std::runtime_error(path + ": cannot write the mission file: " + error.message());
}

}  // namespace auv::sim
