// A mission run folder as layers (README.md, "Mission run"): the files vehicle.yaml writes,
// read by column name; the map through OctoMap itself.
#include <algorithm>
#include <map>
#include <memory>

#include <octomap/OcTree.h>

#include "auv/config/errors.h"
#include "auv/view/folder.h"
#include "auv/view/layers.h"
#include "auv/view/tables.h"

namespace auv::view {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

/// Occupied leaves of the map (pruned leaves keep their size): centre and edge length.
void addMap(Scene& scene, const fs::path& file) {
  // .bt (writeBinary, what the mission handler writes) has its own reader; .ot the generic one.
  std::unique_ptr<octomap::AbstractOcTree> tree;
  if (file.extension() == ".bt") {
    auto binary = std::make_unique<octomap::OcTree>(0.1);
    if (binary->readBinary(file.string())) tree = std::move(binary);
  } else {
    tree.reset(octomap::AbstractOcTree::read(file.string()));
  }
  if (!tree) throw config::ConfigError(file.string() + ": not an OctoMap file (.bt or .ot)");
  auto* map = dynamic_cast<octomap::OcTree*>(tree.get());
  if (!map) throw config::ConfigError(file.string() + ": an OctoMap of another tree type");
  std::vector<float> centre, size;
  for (auto it = map->begin_leafs(), end = map->end_leafs(); it != end; ++it) {
    if (!map->isNodeOccupied(*it)) continue;
    centre.insert(centre.end(), {static_cast<float>(it.getX()), static_cast<float>(it.getY()),
                                 static_cast<float>(it.getZ())});
    size.push_back(static_cast<float>(it.getSize()));
  }
  BufferBuilder buffer;
  buffer.addFloat32("center", centre, 3);
  buffer.addFloat32("size", size, 1);
  scene.addLayer({{"id", "map"},
                  {"type", "voxels"},
                  {"label", "map (occupied voxels)"},
                  {"count", size.size()},
                  {"resolution", map->getResolution()}},
                 std::move(buffer));
}

/// Every tree_<query>.csv as parent -> child segments.
void addTrees(Scene& scene, const fs::path& log) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(log)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("tree_", 0) == 0 && entry.path().extension() == ".csv") {
      files.push_back(entry.path());
    }
  }
  if (files.empty()) return;
  std::sort(files.begin(), files.end());
  std::vector<float> segments;
  for (const auto& file : files) {
    const auto rows = readCsvColumns(file, {"index", "parent", "x", "y", "z"});
    std::map<long, const std::vector<double>*> by_index;
    for (const auto& row : rows) by_index[static_cast<long>(row[0])] = &row;
    for (const auto& row : rows) {
      const auto parent = by_index.find(static_cast<long>(row[1]));
      if (row[1] < 0 || parent == by_index.end()) continue;  // the root
      const std::vector<double>& p = *parent->second;
      for (double v : {p[2], p[3], p[4], row[2], row[3], row[4]}) {
        segments.push_back(static_cast<float>(v));
      }
    }
  }
  BufferBuilder buffer;
  const size_t edges = segments.size() / 6;
  buffer.addFloat32("position", segments, 3);
  scene.addLayer({{"id", "trees"},
                  {"type", "segments"},
                  {"label", "planner trees"},
                  {"count", edges},
                  {"trees", files.size()},
                  {"color", "#7f8c8d"}},
                 std::move(buffer));
}

/// The last path the planner sent for each query (paths.csv holds every one).
void addPaths(Scene& scene, const fs::path& file) {
  const auto rows = readCsvColumns(file, {"query_id", "path_seq", "index", "x", "y", "z"});
  std::map<long, long> last_seq;
  for (const auto& row : rows) {
    auto& seq = last_seq[static_cast<long>(row[0])];
    seq = std::max(seq, static_cast<long>(row[1]));
  }
  std::map<long, std::vector<Eigen::Vector3d>> paths;
  for (const auto& row : rows) {
    if (static_cast<long>(row[1]) == last_seq[static_cast<long>(row[0])]) {
      paths[static_cast<long>(row[0])].push_back({row[3], row[4], row[5]});
    }
  }
  Polylines lines;
  for (const auto& [query, points] : paths) lines.add(points);
  if (lines.lines() == 0) return;
  BufferBuilder buffer;
  buffer.addFloat32("position", lines.xyz, 3);
  buffer.addUint32("start", lines.starts, 1);
  buffer.addUint32("vertices", lines.counts, 1);
  scene.addLayer({{"id", "paths"},
                  {"type", "polylines"},
                  {"label", "planner paths (last per query)"},
                  {"count", lines.lines()},
                  {"color", "#f39c12"}},
                 std::move(buffer));
}

void addPoints(Scene& scene, const std::string& id, const std::string& label,
               const std::string& type, const std::vector<std::vector<double>>& rows,
               const std::string& colour) {
  if (rows.empty()) return;
  std::vector<float> xyz;
  for (const auto& row : rows) {
    for (int i = 0; i < 3; ++i) xyz.push_back(static_cast<float>(row[i]));
  }
  BufferBuilder buffer;
  buffer.addFloat32("position", xyz, 3);
  scene.addLayer(
      {{"id", id}, {"type", type}, {"label", label}, {"count", rows.size()}, {"color", colour}},
      std::move(buffer));
}

}  // namespace

void addTrajectory(Scene& scene, const std::string& id, const std::string& label,
                   const std::vector<StampedPosition>& poses, const std::string& colour,
                   size_t max_points) {
  if (poses.size() < 2) return;
  const size_t step = (poses.size() + max_points - 1) / max_points;
  std::vector<Eigen::Vector3d> points;
  for (size_t i = 0; i < poses.size(); i += step) points.push_back(poses[i].p);
  if (points.back() != poses.back().p) points.push_back(poses.back().p);
  Polylines lines;
  lines.add(points);
  BufferBuilder buffer;
  buffer.addFloat32("position", lines.xyz, 3);
  buffer.addUint32("start", lines.starts, 1);
  buffer.addUint32("vertices", lines.counts, 1);
  scene.addLayer({{"id", id},
                  {"type", "polylines"},
                  {"label", label},
                  {"count", 1},
                  {"poses", poses.size()},
                  {"color", colour}},
                 std::move(buffer));
}

Scene buildRunScene(const fs::path& run, const SceneOptions& /*options*/) {
  Scene scene;
  scene.manifest = {{"kind", "run"},
                    {"name", fs::absolute(run).lexically_normal().filename().string()},
                    {"frame", "world (NED: x north, y east, z down)"},
                    {"layers", json::array()},
                    {"notes", json::array()}};
  const fs::path log = run / "mission";
  std::error_code ec;
  if (fs::is_regular_file(log / "map.bt", ec)) {
    addMap(scene, log / "map.bt");
  } else {
    scene.note("no mission/map.bt (the mission handler writes it when the mission ends)");
  }
  if (fs::is_directory(log, ec)) {
    addTrees(scene, log);
    if (fs::is_regular_file(log / "paths.csv", ec)) addPaths(scene, log / "paths.csv");
    if (fs::is_regular_file(log / "waypoints.csv", ec)) {
      addPoints(scene, "waypoints", "waypoints", "points",
                readCsvColumns(log / "waypoints.csv", {"x", "y", "z"}), "#f1c40f");
    }
  }
  const fs::path truth = run / "ground_truth";
  if (fs::is_regular_file(truth / "trajectory.tum", ec)) {
    addTrajectory(scene, "trajectory_true", "true trajectory", readTum(truth / "trajectory.tum"),
                  "#ecf0f1");
  }
  if (fs::is_regular_file(truth / "navigation.tum", ec)) {
    addTrajectory(scene, "trajectory_estimated", "estimated trajectory (navigation)",
                  readTum(truth / "navigation.tum"), "#2ecc71");
  }
  if (fs::is_regular_file(truth / "collisions.csv", ec)) {
    const auto rows = readCsvColumns(truth / "collisions.csv", {"x", "y", "z"});
    addPoints(scene, "collisions", "collisions", "spheres", rows, "#e74c3c");
    if (rows.empty()) scene.manifest["collisions"] = 0;
  }
  return scene;
}

}  // namespace auv::view
