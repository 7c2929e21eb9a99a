#pragma once
// The simulator's ground truth of a run folder (components/simulator/README.md, "Run folder"),
// what `auv recon evaluate` and `auv recon figures` compare a reconstruction with:
//
//   <run>/scenario.yaml                      world.mesh (+ up_axis, origin, yaw_deg, scale),
//                                            water.visibility
//   <run>/ground_truth/cameras.txt           true intrinsics (COLMAP OPENCV / FULL_OPENCV)
//   <run>/ground_truth/images_<camera>.txt   true world -> camera pose of every rendered frame,
//                                            NAME = "<video file>#<frame>"
//   <run>/ground_truth/trajectory.tum        true body trajectory; navigation.tum the estimate
//   <run>/ground_truth/world.ply             a changed site's world as this visit saw it (world
//                                            NED), used instead of the scenario's mesh
//   <run>/ground_truth/changes.json, .ply    the change since the earlier visit (change_truth.h)
//
// The world frame is NED (x north, y east, z down), the simulator's.

#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "auv/recon/scene/reconstruction.h"

namespace open3d::geometry {
class TriangleMesh;
}

namespace auv::recon::evaluate {

/// One rendered frame with its true pose.
struct GroundTruthFrame {
  std::string camera;  ///< camera id of the rig (left, right, forward)
  std::string video;   ///< video file name (left_0001.mp4)
  int64_t frame = 0;   ///< frame number in the video, from 0
  scene::Image image;  ///< true pose (world -> camera), camera_id of cameras.txt, NAME
};

/// A stamped pose of a TUM trajectory file ("t x y z qx qy qz qw").
struct StampedPose {
  double time = 0;              ///< s
  Eigen::Vector3d position;     ///< m, world
  Eigen::Quaterniond rotation;  ///< body -> world
};

/// Ground-truth key of a frame: "<video stem>#<frame>" (the stem drops the extension, so
/// "left_0001.mp4#12" and a survey index naming "left_0001" meet).
std::string frameKey(const std::string& video, int64_t frame);

class GroundTruth {
 public:
  /// Reads cameras.txt, every images_<camera>.txt and the scenario of `run`. Throws
  /// StageError("evaluate", ...) naming the missing or malformed file. The world mesh is read
  /// on first use (worldMesh()).
  static GroundTruth load(const std::filesystem::path& run);

  const std::filesystem::path& run() const { return run_; }
  /// Cameras of cameras.txt by their id, true intrinsics with distortion.
  const std::map<uint32_t, scene::Camera>& cameras() const { return cameras_; }
  /// Every rendered frame, by frameKey().
  const std::map<std::string, GroundTruthFrame>& frames() const { return frames_; }
  /// The frame of `key`, or nullptr.
  const GroundTruthFrame* find(const std::string& key) const;
  /// Camera names with a ground-truth image file, sorted.
  std::vector<std::string> cameraNames() const;

  /// The scenario's world mesh in the world frame (NED, metres), with its texture if it has
  /// one; read once. Throws StageError naming the scenario or the mesh file.
  std::shared_ptr<const open3d::geometry::TriangleMesh> worldMesh() const;
  std::filesystem::path meshFile() const { return mesh_file_; }
  /// water.visibility of the scenario (m; from the clearest channel's attenuation, 3.912 / a,
  /// when it gives coefficients), 0 when it gives neither.
  double visibility() const { return visibility_; }

  /// trajectory.tum (true) and navigation.tum (the vehicle's estimate); empty when absent.
  std::vector<StampedPose> trueTrajectory() const;
  std::vector<StampedPose> navigationTrajectory() const;

 private:
  std::filesystem::path run_, mesh_file_;
  std::map<uint32_t, scene::Camera> cameras_;
  std::map<std::string, GroundTruthFrame> frames_;
  Eigen::Matrix4d mesh_to_world_ = Eigen::Matrix4d::Identity();
  double visibility_ = 0;
  mutable std::shared_ptr<const open3d::geometry::TriangleMesh> mesh_;
};

/// Reads a TUM trajectory; throws StageError naming the file and line.
std::vector<StampedPose> readTum(const std::filesystem::path& file);

/// The mesh -> world transform of a scenario's `world:` keys (the simulator's
/// Scenario::meshToWorld): translate(origin) * yaw about z * up-axis change * scale.
Eigen::Matrix4d meshToWorld(const std::string& up_axis, const Eigen::Vector3d& origin,
                            double yaw_deg, double scale);

}  // namespace auv::recon::evaluate
