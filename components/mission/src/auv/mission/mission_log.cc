#include "auv/mission/mission_log.h"

#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "auv/mission/mission_executive.h"

namespace auv::mission {
namespace fs = std::filesystem;

namespace {
std::ofstream openCsv(const fs::path& path, const char* header) {
  std::ofstream out(path, std::ios::trunc);
  if (!out) throw std::runtime_error(path.string() + ": cannot write the mission log");
  out.precision(10);
  out << header << "\n" << std::flush;
  return out;
}
}  // namespace

MissionLog::MissionLog(const std::string& dir, const MissionPlan& plan) : dir_(dir) {
  std::error_code error;
  fs::create_directories(dir, error);
  if (error)
    throw std::runtime_error(dir + ": cannot create the mission log folder: " + error.message());
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().filename().string().rfind("tree_", 0) == 0) fs::remove(entry.path());
  }
  std::ofstream(fs::path(dir) / "mission.yaml", std::ios::trunc) << toYaml(plan);
  events_ = openCsv(fs::path(dir) / "events.csv",
                    "t,event,query_index,query_id,waypoint_id,x,y,z,detail");
  waypoints_ = openCsv(fs::path(dir) / "waypoints.csv", "t,query_id,waypoint_id,x,y,z,is_final");
  paths_ = openCsv(fs::path(dir) / "paths.csv", "t,query_id,path_seq,index,x,y,z");
}

MissionLog::~MissionLog() = default;

void MissionLog::event(double t, const std::string& event, const msg::MissionStatus& status,
                       const Eigen::Vector3d& position, const std::string& detail) {
  std::string clean = detail;
  for (char& c : clean) {
    if (c == ',' || c == '\n' || c == '"') c = ';';  // keep one CSV field
  }
  events_ << t << "," << event << "," << status.current_query_index() << ","
          << status.current_query_id() << "," << status.current_waypoint_id() << "," << position.x()
          << "," << position.y() << "," << position.z() << "," << clean << std::endl;
}

void MissionLog::waypoint(double t, const msg::Waypoint& w) {
  waypoints_ << t << "," << w.query_id() << "," << w.waypoint_id() << "," << w.position().x() << ","
             << w.position().y() << "," << w.position().z() << "," << (w.is_final() ? 1 : 0)
             << std::endl;
}

void MissionLog::path(double t, const msg::Path& path) {
  ++path_seq_;
  for (std::size_t i = 0; i < path.poses().size(); ++i) {
    const auto& p = path.poses()[i].position();
    paths_ << t << "," << path.query_id() << "," << path_seq_ << "," << i << "," << p.x() << ","
           << p.y() << "," << p.z() << "\n";
  }
  paths_.flush();
}

void MissionLog::tree(const msg::PlannerTree& tree) { trees_[tree.query_id()] = tree; }

void MissionLog::finish(const msg::MissionStatus& status, const octomap::OcTree* map) {
  for (const auto& [query_id, tree] : trees_) {
    std::ofstream out = openCsv(fs::path(dir_) / ("tree_" + std::to_string(query_id) + ".csv"),
                                "index,parent,x,y,z,cost");
    for (std::size_t i = 0; i < tree.nodes().size(); ++i) {
      const auto& p = tree.nodes()[i];
      out << i << "," << (i < tree.parents().size() ? tree.parents()[i] : -1) << "," << p.x() << ","
          << p.y() << "," << p.z() << "," << (i < tree.costs().size() ? tree.costs()[i] : 0.0)
          << "\n";
    }
  }
  std::ofstream out(fs::path(dir_) / "status.txt", std::ios::trunc);
  out << "mission_id: " << status.mission_id() << "\n"
      << "state: " << toString(status.state()) << "\n"
      << "message: " << status.message() << "\n"
      << "query_count: " << status.query_count() << "\n"
      << "queries_succeeded: " << status.queries_succeeded() << "\n"
      << "queries_failed: " << status.queries_failed() << "\n"
      << "waypoints_received: " << status.waypoints_received() << "\n"
      << "waypoints_reached: " << status.waypoints_reached() << "\n"
      << "waypoints_cancelled: " << status.waypoints_cancelled() << "\n"
      << "recoveries: " << status.recoveries() << "\n";
  if (map != nullptr) {
    // Temporary name, then rename: a reader never sees half a map.
    const fs::path final_path = fs::path(dir_) / "map.bt";
    const fs::path temporary = fs::path(dir_) / "map.bt.part";
    if (map->writeBinaryConst(temporary.string())) fs::rename(temporary, final_path);
  }
  finished_ = true;
}

}  // namespace auv::mission
