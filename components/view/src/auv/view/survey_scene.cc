// A survey folder as layers (README.md, "Survey"): what `auv recon run`, `evaluate` and
// `figures` leave in it, in the truth's frame when `evaluate` aligned the reconstruction.
#include <algorithm>
#include <fstream>
#include <map>
#include <sstream>

#include <open3d/geometry/PointCloud.h>
#include <open3d/io/PointCloudIO.h>
#include <Eigen/Geometry>

#include "auv/config/errors.h"
#include "auv/view/folder.h"
#include "auv/view/layers.h"
#include "auv/view/mesh.h"

namespace auv::view {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

/// evaluation.json's "alignment" (reconstruction -> truth similarity), when there is one.
struct Alignment {
  bool known = false;
  double scale = 1;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Vector3d apply(const Eigen::Vector3d& p) const {
    return scale * (rotation * p) + translation;
  }
};

json readJson(const fs::path& file, Scene& scene) {
  std::ifstream in(file);
  if (!in) return json();
  try {
    return json::parse(in);
  } catch (const std::exception& e) {
    scene.note(file.string() + ": unreadable JSON (" + e.what() + "); ignored");
    return json();
  }
}

Alignment readAlignment(const fs::path& survey, Scene& scene) {
  Alignment a;
  const json evaluation = readJson(survey / "evaluation.json", scene);
  if (!evaluation.is_object() || !evaluation.contains("alignment")) return a;
  try {
    const json& j = evaluation.at("alignment");
    a.scale = j.at("scale").get<double>();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) a.rotation(r, c) = j.at("rotation").at(r).at(c).get<double>();
      a.translation[r] = j.at("translation").at(r).get<double>();
    }
    a.known = true;
  } catch (const std::exception& e) {
    scene.note((survey / "evaluation.json").string() + ": alignment: " + e.what() +
               "; shown in the reconstruction's frame");
  }
  return a;
}

void push(std::vector<float>& out, const Eigen::Vector3d& p) {
  out.insert(out.end(),
             {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())});
}

/// Zoomed in, the page draws only the tiles in view of a finer level; a tile this large keeps
/// the number of objects (draw calls) of a level at 256 at most.
constexpr size_t kTrianglesPerTile = 5000;

void addModel(Scene& scene, const fs::path& obj, const Alignment& align,
              const SceneOptions& options) {
  TexturedMesh mesh = readObj(obj);
  for (size_t i = 0; i < mesh.position.size(); i += 3) {
    const Eigen::Vector3d p =
        align.apply(Eigen::Vector3d(mesh.position[i], mesh.position[i + 1], mesh.position[i + 2]));
    for (int k = 0; k < 3; ++k) mesh.position[i + k] = static_cast<float>(p[k]);
  }
  std::vector<MeshLevel> levels = buildLevels(mesh, options.min_triangles);
  std::map<fs::path, std::string> route_of;
  size_t default_level = levels.size() - 1;
  for (size_t k = 0; k < levels.size(); ++k) {
    if (levels[k].mesh.triangles() <= options.default_triangles) {
      default_level = k;
      break;
    }
  }
  json lod = json::array();
  auto groupsJson = [&](const std::vector<TexturedMesh::Group>& list) {
    json groups = json::array();
    for (const auto& g : list) {
      std::string texture;
      if (!g.texture.empty()) {
        auto it = route_of.find(g.texture);
        if (it == route_of.end()) it = route_of.emplace(g.texture, scene.addFile(g.texture)).first;
        texture = it->second;
      }
      groups.push_back({{"start", g.first_index}, {"count", g.index_count}, {"texture", texture}});
    }
    return groups;
  };
  for (size_t k = 0; k < levels.size(); ++k) {
    TexturedMesh& m = levels[k].mesh;
    json tiles = json::array();
    for (const Tile& t : tileMesh(m, kTrianglesPerTile)) {
      tiles.push_back({{"groups", groupsJson(t.groups)},
                       {"center", {t.center[0], t.center[1], t.center[2]}},
                       {"radius", t.radius}});
    }
    const json groups = groupsJson(m.groups);
    BufferBuilder buffer;
    buffer.addFloat32("position", m.position, 3);
    if (!m.uv.empty()) buffer.addFloat32("uv", m.uv, 2);
    if (!m.color.empty()) buffer.addUint8("color", m.color, 3);
    buffer.addUint32("index", m.index, 3);
    const std::string id = "model_" + std::to_string(k);
    lod.push_back({{"layer", id},
                   {"triangles", m.triangles()},
                   {"error", levels[k].error},
                   {"vertexColours", !m.color.empty()}});
    scene.addLayer({{"id", id},
                    {"type", "mesh"},
                    {"label", "textured model"},
                    {"level", k},
                    {"count", m.triangles()},
                    {"groups", groups},
                    {"tiles", tiles},
                    {"lazy", k != default_level && k != levels.size() - 1}},
                   std::move(buffer));
  }
  scene.manifest["model"] = {{"levels", lod},
                             {"default", default_level},
                             {"coarsest", levels.size() - 1},
                             {"triangles", mesh.triangles()}};
}

/// A PLY cloud (Open3D), thinned by a regular stride to `max_points`.
void addCloud(Scene& scene, const fs::path& ply, const std::string& id, const std::string& label,
              const Alignment* align, size_t max_points, json extra = json::object()) {
  open3d::geometry::PointCloud cloud;
  if (!open3d::io::ReadPointCloud(ply.string(), cloud) || cloud.points_.empty()) {
    scene.note(ply.string() + ": unreadable or empty point cloud; not shown");
    return;
  }
  const size_t n = cloud.points_.size();
  const size_t step = (n + max_points - 1) / max_points;
  std::vector<float> xyz;
  std::vector<uint8_t> rgb;
  for (size_t i = 0; i < n; i += step) {
    push(xyz, align ? align->apply(cloud.points_[i]) : cloud.points_[i]);
    const Eigen::Vector3d c = cloud.HasColors() ? cloud.colors_[i] : Eigen::Vector3d(0.7, 0.7, 0.7);
    for (int k = 0; k < 3; ++k)
      rgb.push_back(static_cast<uint8_t>(std::clamp(c[k], 0.0, 1.0) * 255 + 0.5));
  }
  BufferBuilder buffer;
  buffer.addFloat32("position", xyz, 3);
  buffer.addUint8("color", rgb, 3);
  json layer = {
      {"id", id}, {"type", "points"}, {"label", label}, {"count", xyz.size() / 3}, {"total", n}};
  layer.update(extra);
  scene.addLayer(std::move(layer), std::move(buffer));
}

struct SparseImage {
  std::string name, camera;
  Eigen::Vector3d centre;
  Eigen::Matrix3d rotation_cw;
};

/// sparse/images.txt (COLMAP text: "ID QW QX QY QZ TX TY TZ CAMERA_ID NAME", then a line of
/// observations), sorted by name.
std::vector<SparseImage> readImages(const fs::path& file, const Alignment& align) {
  std::ifstream in(file);
  if (!in) throw config::ConfigError(file.string() + ": cannot read");
  std::vector<SparseImage> images;
  std::string line;
  size_t number = 0;
  bool pose_line = true;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line[0] == '#') continue;
    if (!pose_line) {
      pose_line = true;
      continue;
    }
    std::istringstream s(line);
    long id = 0, camera_id = 0;
    double qw, qx, qy, qz, tx, ty, tz;
    SparseImage image;
    if (!(s >> id >> qw >> qx >> qy >> qz >> tx >> ty >> tz >> camera_id >> image.name)) {
      if (line.find_first_not_of(" \r") == std::string::npos) continue;
      throw config::ConfigError(file.string() + ":" + std::to_string(number) +
                                ": expected 'IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME'");
    }
    pose_line = false;
    const Eigen::Matrix3d r = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
    const Eigen::Vector3d centre = -r.transpose() * Eigen::Vector3d(tx, ty, tz);
    image.centre = align.apply(centre);
    image.rotation_cw = r * align.rotation.transpose();
    const size_t slash = image.name.find('/');
    image.camera = slash == std::string::npos ? "camera" : image.name.substr(0, slash);
    images.push_back(image);
  }
  std::sort(images.begin(), images.end(),
            [](const SparseImage& a, const SparseImage& b) { return a.name < b.name; });
  return images;
}

void addSparse(Scene& scene, const fs::path& sparse, const Alignment& align) {
  std::ifstream in(sparse / "points3D.txt");
  std::vector<float> xyz;
  std::vector<uint8_t> rgb;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    long id;
    double x, y, z;
    int r, g, b;
    if (!(s >> id >> x >> y >> z >> r >> g >> b)) continue;
    push(xyz, align.apply({x, y, z}));
    rgb.insert(rgb.end(),
               {static_cast<uint8_t>(r), static_cast<uint8_t>(g), static_cast<uint8_t>(b)});
  }
  if (!xyz.empty()) {
    BufferBuilder buffer;
    buffer.addFloat32("position", xyz, 3);
    buffer.addUint8("color", rgb, 3);
    scene.addLayer({{"id", "sparse"},
                    {"type", "points"},
                    {"label", "sparse points (SfM)"},
                    {"count", xyz.size() / 3},
                    {"pointSize", 3},
                    {"visible", false}},
                   std::move(buffer));
  }
  const std::vector<SparseImage> images = readImages(sparse / "images.txt", align);
  if (images.empty()) return;
  std::vector<std::string> cameras;
  for (const auto& im : images) cameras.push_back(im.camera);
  std::sort(cameras.begin(), cameras.end());
  cameras.erase(std::unique(cameras.begin(), cameras.end()), cameras.end());
  std::vector<float> centre, axes;
  std::vector<uint8_t> camera;
  std::map<std::string, std::vector<Eigen::Vector3d>> path;
  for (const auto& im : images) {
    push(centre, im.centre);
    for (int r = 0; r < 3; ++r) push(axes, im.rotation_cw.row(r).transpose());  // x, y, z axes
    camera.push_back(static_cast<uint8_t>(std::find(cameras.begin(), cameras.end(), im.camera) -
                                          cameras.begin()));
    path[im.camera].push_back(im.centre);
  }
  BufferBuilder buffer;
  buffer.addFloat32("center", centre, 3);
  buffer.addFloat32("axes", axes, 9);
  buffer.addUint8("camera", camera, 1);
  scene.addLayer({{"id", "cameras"},
                  {"type", "cameras"},
                  {"label", "SfM cameras"},
                  {"count", images.size()},
                  {"cameras", cameras}},
                 std::move(buffer));
  // Figure 20's SfM trajectory: each camera's centres in name (= time) order.
  Polylines lines;
  for (const auto& [name, points] : path) lines.add(points);
  if (lines.lines() == 0) return;
  BufferBuilder trajectory;
  trajectory.addFloat32("position", lines.xyz, 3);
  trajectory.addUint32("start", lines.starts, 1);
  trajectory.addUint32("vertices", lines.counts, 1);
  scene.addLayer({{"id", "trajectory_sfm"},
                  {"type", "polylines"},
                  {"label", "SfM camera trajectory"},
                  {"count", lines.lines()},
                  {"color", "#e74c3c"}},
                 std::move(trajectory));
}

/// Figure 20's other two lines: navigation and truth of the simulated run, clipped to the
/// recordings' span (frames.csv sim_time_s) as `auv recon figures` does.
void addNavigation(Scene& scene, const fs::path& survey) {
  const json simulation = readJson(survey / "simulation.json", scene);
  if (!simulation.is_object() || !simulation.contains("ground_truth_run")) return;
  fs::path run = simulation["ground_truth_run"].get<std::string>();
  if (run.is_relative()) run = survey / run;
  if (!fs::is_regular_file(run / "ground_truth" / "navigation.tum")) {
    scene.note((run / "ground_truth" / "navigation.tum").string() +
               ": not found (simulation.json's ground_truth_run); no navigation shown");
    return;
  }
  double first = 1e300, last = -1e300;
  std::error_code ec;
  for (const auto& entry : fs::recursive_directory_iterator(survey / "recordings", ec)) {
    const std::string name = entry.path().filename().string();
    if (name.size() < 11 || name.compare(name.size() - 11, 11, ".frames.csv") != 0) continue;
    try {
      for (const auto& row : readCsvColumns(entry.path(), {"sim_time_s"})) {
        first = std::min(first, row[0]);
        last = std::max(last, row[0]);
      }
    } catch (const std::exception&) {
      // a real camera's sidecar has no simulated time
    }
  }
  auto clip = [&](std::vector<StampedPosition> poses) {
    if (first > last) return poses;
    poses.erase(
        std::remove_if(poses.begin(), poses.end(),
                       [&](const StampedPosition& p) { return p.t < first - 5 || p.t > last + 5; }),
        poses.end());
    return poses;
  };
  addTrajectory(scene, "trajectory_estimated", "vehicle navigation (dead reckoning)",
                clip(readTum(run / "ground_truth" / "navigation.tum")), "#2ecc71");
  if (fs::is_regular_file(run / "ground_truth" / "trajectory.tum")) {
    addTrajectory(scene, "trajectory_true", "true trajectory",
                  clip(readTum(run / "ground_truth" / "trajectory.tum")), "#ecf0f1");
  }
}

}  // namespace

Scene buildSurveyScene(const fs::path& survey, const SceneOptions& options) {
  Scene scene;
  const Alignment align = readAlignment(survey, scene);
  scene.manifest = {
      {"kind", "survey"},
      {"name", fs::absolute(survey).lexically_normal().filename().string()},
      {"frame", align.known ? "world (NED), aligned by evaluation.json" : "reconstruction (SfM)"},
      {"layers", json::array()},
      {"notes", scene.manifest.value("notes", json::array())}};
  std::error_code ec;
  if (fs::is_regular_file(survey / "textured" / "model.obj", ec)) {
    addModel(scene, survey / "textured" / "model.obj", align, options);
  } else {
    scene.note("no textured/model.obj (`auv recon texture` writes it)");
  }
  if (fs::is_regular_file(survey / "dense" / "fused.ply", ec)) {
    addCloud(scene, survey / "dense" / "fused.ply", "dense", "dense cloud", &align,
             options.max_points, {{"visible", !scene.manifest.contains("model")}});
  }
  if (fs::is_regular_file(survey / "sparse" / "images.txt", ec)) {
    addSparse(scene, survey / "sparse", align);
  }
  // Figure 19: figures/cameras.ply is in the truth's frame when `figures` had the truth.
  const fs::path contribution = survey / "figures" / "cameras.ply";
  if (fs::is_regular_file(contribution, ec)) {
    const json report = readJson(survey / "report.json", scene);
    const bool world = report.is_object() && report.contains("figures") &&
                       report["figures"].value("aligned_to_truth", false);
    if (world != align.known) {
      scene.note("figures/cameras.ply is in " +
                 std::string(world ? "the truth's frame" : "its own top-down frame") +
                 ", the other layers are not: shown on its own");
    }
    addCloud(scene, contribution, "contribution", "per-camera contribution (Fig. 19)", nullptr,
             options.max_points,
             {{"visible", false},
              {"legend",
               "one camera red/green/blue in name order, two: "
               "their mixtures, three: white"}});
  } else {
    scene.note("no figures/cameras.ply (`auv recon figures` writes the per-camera contribution)");
  }
  if (align.known) {
    addNavigation(scene, survey);
  } else {
    scene.note("navigation against SfM (Fig. 20) needs the alignment of `auv recon evaluate`");
  }
  return scene;
}

}  // namespace auv::view
