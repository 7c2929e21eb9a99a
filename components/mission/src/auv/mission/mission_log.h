#pragma once
// What the mission handler records for the mission report (`auv mission report`), in
// `<log_dir>/` (formats in components/mission/README.md):
//   mission.yaml        the mission's queries (as started)
//   events.csv          t,event,query_index,query_id,waypoint_id,x,y,z,detail
//   waypoints.csv       t,query_id,waypoint_id,x,y,z,is_final (every planner/waypoint received)
//   paths.csv           t,query_id,path_seq,index,x,y,z   (every planner/path received)
//   tree_<query>.csv    index,parent,x,y,z,cost           (the planner's last tree per query,
//                       written when a tree of another query arrives, and on finish())
//   map.bt              the occupancy map when the mission ended (OctoMap binary)
//   status.txt          the final MissionStatus, one "field: value" per line
// Lines are flushed as written, so a crash loses at most the last one.

#include <cstdint>
#include <fstream>
#include <map>
#include <string>

#include <octomap/OcTree.h>
#include <Eigen/Core>

#include "auv/mission/mission_plan.h"
#include "auv/msg/all.h"

namespace auv::mission {

class MissionLog {
 public:
  /// Creates `dir` (and parents); throws std::runtime_error naming it on failure. Files of an
  /// earlier mission in the same folder are replaced; with `resume` (the same mission, by a
  /// restarted handler) they are appended to.
  MissionLog(const std::string& dir, const MissionPlan& plan, bool resume = false);
  ~MissionLog();

  void event(double t, const std::string& event, const msg::MissionStatus& status,
             const Eigen::Vector3d& position, const std::string& detail);
  void waypoint(double t, const msg::Waypoint& waypoint);
  void path(double t, const msg::Path& path);
  /// Keeps the newest tree of its query; writes (and forgets) those of other queries.
  void tree(const msg::PlannerTree& tree);
  /// Writes the tree held, the final status and the map (may be null).
  void finish(const msg::MissionStatus& status, const octomap::OcTree* map);
  const std::string& dir() const { return dir_; }

 private:
  std::string dir_;
  std::ofstream events_;
  std::ofstream waypoints_;
  std::ofstream paths_;
  uint64_t path_seq_ = 0;
  void writeTree(const msg::PlannerTree& tree) const;

  std::map<uint64_t, msg::PlannerTree> trees_;  // of the newest query (a late one's too)
  bool finished_ = false;
};

}  // namespace auv::mission
