#include "auv/recon/evaluate/ground_truth.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <mutex>
#include <set>
#include <sstream>

#include <open3d/geometry/TriangleMesh.h>
#include <yaml-cpp/yaml.h>

#include "auv/config/yaml_section.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/scene/colmap_text.h"
#include "auv/recon/scene/mesh_io.h"

namespace fs = std::filesystem;

namespace auv::recon::evaluate {
namespace {

constexpr const char* kStage = "evaluate";
constexpr double kDeg = M_PI / 180.0;

std::mutex mesh_mutex;

}  // namespace

std::string frameKey(const std::string& video, int64_t frame) {
  return fs::path(video).stem().string() + "#" + std::to_string(frame);
}

Eigen::Matrix4d meshToWorld(const std::string& up_axis, const Eigen::Vector3d& origin,
                            double yaw_deg, double scale) {
  // z-up: (x, y, z) -> (x, -y, -z); y-up: (x, y, z) -> (x, z, -y) (both rotations), as the
  // simulator places a mesh (Scenario::meshToWorld).
  Eigen::Matrix3d up_to_ned;
  if (up_axis == "y") {
    up_to_ned << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  } else {
    up_to_ned << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  }
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.topLeftCorner<3, 3>() =
      Eigen::AngleAxisd(yaw_deg * kDeg, Eigen::Vector3d::UnitZ()).toRotationMatrix() * up_to_ned *
      scale;
  T.topRightCorner<3, 1>() = origin;
  return T;
}

GroundTruth GroundTruth::load(const fs::path& run) {
  GroundTruth gt;
  gt.run_ = run;
  std::error_code error;
  if (!fs::is_directory(run, error)) {
    throw StageError(kStage, "ground truth: " + run.string() + ": no such run folder");
  }
  const fs::path truth = run / "ground_truth";
  const fs::path cameras_file = truth / "cameras.txt";
  if (!fs::exists(cameras_file, error)) {
    throw StageError(kStage, "ground truth: " + cameras_file.string() +
                                 " not found (render the run's cameras with `auv sim render " +
                                 run.string() + "`)");
  }
  try {
    gt.cameras_ = scene::readColmapCameras(cameras_file);
    for (const auto& entry : fs::directory_iterator(truth)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind("images_", 0) != 0 || entry.path().extension() != ".txt") continue;
      const std::string camera = entry.path().stem().string().substr(7);
      for (auto& [id, image] : scene::readColmapImages(entry.path())) {
        const size_t hash = image.name.rfind('#');
        if (hash == std::string::npos || hash + 1 == image.name.size()) {
          throw std::runtime_error(entry.path().string() + ": image " + std::to_string(id) +
                                   ": NAME '" + image.name + "' is not <video>#<frame>");
        }
        GroundTruthFrame frame;
        frame.camera = camera;
        frame.video = image.name.substr(0, hash);
        try {
          size_t used = 0;
          frame.frame = std::stoll(image.name.substr(hash + 1), &used);
          if (used != image.name.size() - hash - 1) throw std::invalid_argument("trailing");
        } catch (const std::exception&) {
          throw std::runtime_error(entry.path().string() + ": image " + std::to_string(id) +
                                   ": NAME '" + image.name + "' has no frame number after '#'");
        }
        if (!gt.cameras_.count(image.camera_id)) {
          throw std::runtime_error(entry.path().string() + ": image " + image.name +
                                   " names camera " + std::to_string(image.camera_id) + ", which " +
                                   cameras_file.string() + " does not have");
        }
        frame.image = std::move(image);
        const std::string key = frameKey(frame.video, frame.frame);
        gt.frames_.emplace(key, std::move(frame));
      }
    }
  } catch (const StageError&) {
    throw;
  } catch (const std::exception& e) {
    throw StageError(kStage, std::string("ground truth: ") + e.what());
  }
  if (gt.frames_.empty()) {
    throw StageError(kStage, "ground truth: " + truth.string() +
                                 " has no images_<camera>.txt with frames (was `auv sim render` "
                                 "run on " +
                                 run.string() + "?)");
  }

  // The scenario the run used (world.mesh made absolute by the simulator; a relative path is
  // taken relative to the scenario file, as the simulator does).
  const fs::path scenario = run / "scenario.yaml";
  try {
    const YAML::Node root = config::loadYamlFile(scenario.string()).node();
    const YAML::Node world = root["world"];
    if (!world || !world["mesh"]) throw std::runtime_error("world.mesh: missing");
    fs::path mesh = world["mesh"].as<std::string>();
    if (mesh.is_relative()) mesh = scenario.parent_path() / mesh;
    gt.mesh_file_ = mesh;
    const std::string up = world["up_axis"] ? world["up_axis"].as<std::string>() : "z";
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    if (world["origin"]) {
      const auto o = world["origin"].as<std::vector<double>>();
      if (o.size() != 3) throw std::runtime_error("world.origin: expected [x, y, z]");
      origin = Eigen::Vector3d(o[0], o[1], o[2]);
    }
    const double yaw = world["yaw_deg"] ? world["yaw_deg"].as<double>() : 0.0;
    const double scale = world["scale"] ? world["scale"].as<double>() : 1.0;
    gt.mesh_to_world_ = meshToWorld(up, origin, yaw, scale);
    const YAML::Node water = root["water"];
    if (water && water["visibility"]) {
      gt.visibility_ = water["visibility"].as<double>();
    } else if (water && water["attenuation"]) {
      // The simulator's definition (Koschmieder, 2 % contrast) for the clearest channel.
      const auto a = water["attenuation"].as<std::vector<double>>();
      const double clearest = a.empty() ? 0.0 : *std::min_element(a.begin(), a.end());
      if (clearest > 0) gt.visibility_ = 3.912 / clearest;
    }
  } catch (const std::exception& e) {
    throw StageError(kStage, "ground truth: " + scenario.string() + ": " + e.what());
  }
  // A visit of a site that changed (the scenario's `changes:`): the simulator writes the world
  // as this visit saw it, already in world NED; the scenario's mesh is the earlier visit's.
  const fs::path changed_world = truth / "world.ply";
  if (fs::exists(changed_world)) {
    gt.mesh_file_ = changed_world;
    gt.mesh_to_world_ = Eigen::Matrix4d::Identity();
  }
  return gt;
}

const GroundTruthFrame* GroundTruth::find(const std::string& key) const {
  const auto it = frames_.find(key);
  return it == frames_.end() ? nullptr : &it->second;
}

std::vector<std::string> GroundTruth::cameraNames() const {
  std::set<std::string> names;
  for (const auto& [key, frame] : frames_) names.insert(frame.camera);
  return {names.begin(), names.end()};
}

std::shared_ptr<const open3d::geometry::TriangleMesh> GroundTruth::worldMesh() const {
  std::lock_guard<std::mutex> lock(mesh_mutex);
  if (mesh_) return mesh_;
  std::error_code error;
  if (!fs::exists(mesh_file_, error)) {
    throw StageError(kStage, "ground truth: world mesh " + mesh_file_.string() +
                                 " (world.mesh of " + (run_ / "scenario.yaml").string() +
                                 ") not found");
  }
  auto mesh = std::make_shared<open3d::geometry::TriangleMesh>();
  if (!scene::readTriangleMesh(mesh_file_, *mesh) || mesh->triangles_.empty()) {
    throw StageError(kStage,
                     "ground truth: world mesh " + mesh_file_.string() + ": unreadable or empty");
  }
  mesh->Transform(mesh_to_world_);
  mesh_ = mesh;
  return mesh_;
}

std::vector<StampedPose> readTum(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw StageError(kStage, file.string() + ": cannot read");
  std::vector<StampedPose> poses;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    const size_t start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos || line[start] == '#') continue;
    std::istringstream fields(line);
    StampedPose pose;
    double qx, qy, qz, qw;
    if (!(fields >> pose.time >> pose.position.x() >> pose.position.y() >> pose.position.z() >>
          qx >> qy >> qz >> qw)) {
      throw StageError(kStage, file.string() + ":" + std::to_string(number) +
                                   ": expected 't x y z qx qy qz qw'");
    }
    pose.rotation = Eigen::Quaterniond(qw, qx, qy, qz);
    if (!(std::abs(pose.rotation.norm() - 1.0) < 1e-2)) {
      throw StageError(
          kStage, file.string() + ":" + std::to_string(number) + ": quaternion is not unit length");
    }
    pose.rotation.normalize();
    poses.push_back(pose);
  }
  return poses;
}

std::vector<StampedPose> GroundTruth::trueTrajectory() const {
  const fs::path file = run_ / "ground_truth" / "trajectory.tum";
  return fs::exists(file) ? readTum(file) : std::vector<StampedPose>{};
}

std::vector<StampedPose> GroundTruth::navigationTrajectory() const {
  const fs::path file = run_ / "ground_truth" / "navigation.tum";
  return fs::exists(file) ? readTum(file) : std::vector<StampedPose>{};
}

}  // namespace auv::recon::evaluate
