#pragma once
// A mission: start-to-goal queries run in order (docs/paper.md §2.3), read from a YAML file
// (format in components/mission/README.md) or received in a StartMissionRequest.

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "auv/config/errors.h"
#include "auv/msg/all.h"

namespace auv::mission {

/// A malformed or unacceptable mission; the message names the file/query and the field (the
/// user's input: exit code 2).
class MissionError : public config::ConfigError {
 public:
  using config::ConfigError::ConfigError;
};

/// One query: everything a PlannerQuery carries except ids, stamps and the start (the vehicle's
/// position when the query begins).
struct MissionQuery {
  std::string name;
  Eigen::Vector3d goal{0, 0, 0};        ///< m NED
  double goal_tolerance = 1.5;          ///< m, ε_goal
  double time_budget = 0.0;             ///< s to the first waypoint; 0 = the planner's default
  bool visibility_objective = true;     ///< false: path length only
  double expected_distance = 1.0;       ///< m, d_e of Eq. (1)
  double admissible_range = 1.0;        ///< m, Δd_a of Eq. (1)
  Eigen::Vector3d bounds_min{0, 0, 0};  ///< m NED, sampling region
  Eigen::Vector3d bounds_max{0, 0, 0};
  bool fixed_depth = false;  ///< plan in the plane z = depth
  /// m, depth of the plane; unset = the vehicle's depth when the query starts.
  std::optional<double> depth;
  /// m, depth band of 3-D planning (fixed_depth false), both or neither: the planner samples
  /// and keeps min_depth <= z <= max_depth inside the bounds' z-range. Unset: the z-range.
  std::optional<double> min_depth;
  std::optional<double> max_depth;
  /// m, water kept between the planner's clearance sphere and known seabed below; 0 = none.
  double min_altitude = 0.0;
};

struct MissionPlan {
  std::string name;  ///< becomes the mission id prefix
  std::vector<MissionQuery> queries;
};

/// Reads and checks a mission file. Throws MissionError naming the file and the field.
MissionPlan loadMissionFile(const std::string& path);
/// Parses mission YAML text; `source` names it in errors.
MissionPlan parseMission(const std::string& yaml_text, const std::string& source);
/// Writes `plan` as mission YAML (what loadMissionFile reads back).
std::string toYaml(const MissionPlan& plan);

/// Checks what can be checked without a map: finite values, ranges, goal inside the bounds,
/// bounds non-empty, the depth band (both ends, min < max, inside the bounds' z-range, not
/// with fixed_depth, the goal inside it), min_altitude >= 0. Throws MissionError naming
/// `source`, the query and the field.
void checkQuery(const MissionQuery& query, const std::string& source);

/// The PlannerQuery for `query` (query_id, start and stamp left for the caller; depth NaN when
/// the query has none: the mission handler fills in the vehicle's depth; min_depth and
/// max_depth 0 without a band).
msg::PlannerQuery toPlannerQuery(const MissionQuery& query);
/// Back from a PlannerQuery (name "query <i>").
MissionQuery fromPlannerQuery(const msg::PlannerQuery& query, std::size_t index);

}  // namespace auv::mission
