#pragma once
// Which folder `auv view` was given and the scene made of it (README.md, "What each view
// shows"). A folder that is neither a survey nor a mission run is a ConfigError (exit 2) that
// names it and what was looked for.

#include <filesystem>
#include <string>

#include "auv/view/scene.h"

namespace auv::view {

enum class FolderKind { kSurvey, kRun };

/// kSurvey: textured/model.obj, dense/fused.ply or sparse/images.txt (auv recon run);
/// kRun: mission/map.bt, mission/events.csv or ground_truth/trajectory.tum (vehicle.yaml).
/// Throws config::ConfigError for a missing folder, a file, or a folder of neither kind.
FolderKind detectFolder(const std::filesystem::path& folder);

/// The survey's layers: LODs of the textured model, dense cloud, sparse points and cameras,
/// per-camera contribution (figures/cameras.ply), navigation against SfM cameras.
Scene buildSurveyScene(const std::filesystem::path& survey, const SceneOptions& options);
/// The run's layers: map voxels, planner trees, last paths, waypoints, true and estimated
/// trajectories, collisions.
Scene buildRunScene(const std::filesystem::path& run, const SceneOptions& options);

}  // namespace auv::view
