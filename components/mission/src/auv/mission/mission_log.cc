#include "auv/mission/mission_log.h"

#include <cstdio>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "auv/mission/mission_executive.h"

namespace auv::mission {
namespace fs = std::filesystem;

namespace {
bool endsWithNewline(const fs::path& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in || in.tellg() == 0) return true;
  in.seekg(-1, std::ios::end);
  return in.get() == '\n';
}

/// Appending, the header is written only to a new or empty file.
std::ofstream openCsv(const fs::path& path, const char* header, bool append) {
  std::error_code error;
  const bool has_header = append && fs::exists(path, error) && fs::file_size(path, error) > 0;
  std::ofstream out(path, append ? std::ios::app : std::ios::trunc);
  if (!out) throw std::runtime_error(path.string() + ": cannot write the mission log");
  out.precision(10);
  if (!has_header) {
    out << header << "\n" << std::flush;
  } else if (!endsWithNewline(path)) {
    out << "\n" << std::flush;  // a line cut by the crash stays a line of its own
  }
  return out;
}
/// The path_seq of the last row of paths.csv (0: none).
uint64_t lastPathSeq(const fs::path& path) {
  std::ifstream in(path);
  std::string line, last;
  while (std::getline(in, line)) {
    if (!line.empty()) last = line;
  }
  std::istringstream row(last);
  std::string t, query, seq;
  if (!std::getline(row, t, ',') || !std::getline(row, query, ',') || !std::getline(row, seq, ','))
    return 0;
  try {
    return std::stoull(seq);
  } catch (const std::exception&) {
    return 0;  // the header, or a line cut by a crash
  }
}
}  // namespace

MissionLog::MissionLog(const std::string& dir, const MissionPlan& plan, bool resume) : dir_(dir) {
  std::error_code error;
  fs::create_directories(dir, error);
  if (error)
    throw std::runtime_error(dir + ": cannot create the mission log folder: " + error.message());
  if (!resume) {
    for (const auto& entry : fs::directory_iterator(dir)) {
      if (entry.path().filename().string().rfind("tree_", 0) == 0) fs::remove(entry.path());
    }
    std::ofstream(fs::path(dir) / "mission.yaml", std::ios::trunc) << toYaml(plan);
  }
  events_ = openCsv(fs::path(dir) / "events.csv",
                    "t,event,query_index,query_id,waypoint_id,x,y,z,detail", resume);
  waypoints_ =
      openCsv(fs::path(dir) / "waypoints.csv", "t,query_id,waypoint_id,x,y,z,is_final", resume);
  if (resume) path_seq_ = lastPathSeq(fs::path(dir) / "paths.csv");  // numbers go on
  paths_ = openCsv(fs::path(dir) / "paths.csv", "t,query_id,path_seq,index,x,y,z", resume);
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

void MissionLog::tree(const msg::PlannerTree& tree) {
  // A tree of another query: the planner has moved on, so the trees held are final. Written
  // now instead of at the end, memory stays one tree however long the mission (the soak's
  // handler grew by each query's 20 000-node tree, 20 % in 2 h), and a crash keeps them.
  for (auto held = trees_.begin(); held != trees_.end();) {
    if (held->first == tree.query_id()) {
      ++held;
      continue;
    }
    writeTree(held->second);
    held = trees_.erase(held);
  }
  trees_[tree.query_id()] = tree;
}

void MissionLog::writeTree(const msg::PlannerTree& tree) const {
  std::ofstream out = openCsv(fs::path(dir_) / ("tree_" + std::to_string(tree.query_id()) + ".csv"),
                              "index,parent,x,y,z,cost", /*append=*/false);
  for (std::size_t i = 0; i < tree.nodes().size(); ++i) {
    const auto& p = tree.nodes()[i];
    out << i << "," << (i < tree.parents().size() ? tree.parents()[i] : -1) << "," << p.x() << ","
        << p.y() << "," << p.z() << "," << (i < tree.costs().size() ? tree.costs()[i] : 0.0)
        << "\n";
  }
}

void MissionLog::finish(const msg::MissionStatus& status, const octomap::OcTree* map) {
  for (const auto& held : trees_) writeTree(held.second);
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
