#pragma once
// The bridge's visual channels in Foxglove's own schemas, JSON-encoded (what Foxglove and
// Lichtblick draw in their 3D and Image panels without code of ours, and what `auv view`'s
// live mode reads): the OctoMap as foxglove.SceneUpdate cubes, the planner's tree and path as
// line primitives, the vehicle and its trajectories, foxglove.FrameTransform for the vehicle
// pose and foxglove.CompressedImage for camera frames. Coordinates stay in the project's
// `world` frame (NED: z down; idl/README.md). No DDS here: message structs in, JSON out.

#include <cstdint>
#include <deque>
#include <string>

#include <octomap/OcTree.h>
#include <nlohmann/json.hpp>

#include "auv/msg/all.h"

namespace auv::foxglove_bridge {

// Channel names and schema names: stable, `auv view` and users' layouts rely on them.
constexpr const char* kMapChannel = "/foxglove/map";
constexpr const char* kPlannerChannel = "/foxglove/planner";
constexpr const char* kVehicleChannel = "/foxglove/vehicle";
constexpr const char* kTfChannel = "/tf";
constexpr const char* kCameraChannelPrefix = "/foxglove/camera/";
constexpr const char* kSceneUpdate = "foxglove.SceneUpdate";
constexpr const char* kFrameTransform = "foxglove.FrameTransform";
constexpr const char* kCompressedImage = "foxglove.CompressedImage";

/// The JSON schema (schemaEncoding `jsonschema`) of `schema_name`, one of the three above.
const std::string& jsonSchema(const std::string& schema_name);

struct MapStyle {
  bool show_free = false;     ///< free leaves as faint cubes too
  bool show_unknown = false;  ///< unknown cells inside the known extent as faint cubes
  size_t max_cubes = 200000;  ///< cubes per update at most (occupied first)
};

/// foxglove.SceneUpdate with entity "map" in frame "world": one cube per occupied leaf (its
/// size), coloured by depth; free and unknown cells per `style`. `truncated` is set when
/// max_cubes cut it short.
nlohmann::json mapScene(const octomap::OcTree& tree, const MapStyle& style, int64_t stamp_ns,
                        bool* truncated = nullptr);
/// Entity "tree": the planner tree's edges as one line list (node to parent).
nlohmann::json treeScene(const msg::PlannerTree& tree);
/// Entity "path": the planner's path as a line strip.
nlohmann::json pathScene(const msg::Path& path);

/// A trajectory kept for drawing: points closer than `min_step` m to the last are skipped,
/// the oldest go beyond `max_points`.
class Trajectory {
 public:
  Trajectory(double min_step, size_t max_points) : min_step_(min_step), max_points_(max_points) {}
  /// True when the point was kept.
  bool add(double x, double y, double z);
  const std::deque<msg::Point>& points() const { return points_; }

 private:
  double min_step_;
  size_t max_points_;
  std::deque<msg::Point> points_;
};

/// SceneUpdate on /foxglove/vehicle: entity "vehicle" (a box of the vehicle's size in frame
/// "vehicle", frame-locked), "trajectory_estimated" and "trajectory_true" (line strips in
/// "world"; left out when empty).
nlohmann::json vehicleScene(const Trajectory& estimated, const Trajectory& truth, int64_t stamp_ns,
                            double length, double width);
/// foxglove.FrameTransform world -> vehicle from an odometry pose.
nlohmann::json vehicleTransform(const msg::Odometry& odometry);
/// The frame Foxglove and Lichtblick display by default ("map", REP-105), z up: x east, y north.
constexpr const char* kDisplayFrame = "map";
/// foxglove.FrameTransform map -> world: the NED `world` (x north, y east, z down) in the z-up
/// display frame, so a 3-D panel shows the site the right way up without settings.
nlohmann::json displayFrameTransform(int64_t stamp_ns);
/// foxglove.CompressedImage (data in base64).
nlohmann::json compressedImage(const msg::CompressedImage& image);
/// The camera channel of a CompressedImage topic: "camera/left/compressed" ->
/// "/foxglove/camera/left" (a leading "camera/" and a trailing "/compressed" dropped).
std::string cameraChannel(const std::string& topic);

std::string base64(const uint8_t* data, size_t size);

}  // namespace auv::foxglove_bridge
