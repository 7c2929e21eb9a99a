#include "auv/view/folder.h"

#include "auv/config/errors.h"

namespace auv::view {
namespace fs = std::filesystem;

FolderKind detectFolder(const fs::path& folder) {
  std::error_code ec;
  if (!fs::exists(folder, ec)) {
    throw config::ConfigError(folder.string() + ": no such folder");
  }
  if (!fs::is_directory(folder, ec)) {
    throw config::ConfigError(folder.string() +
                              ": not a folder (give a survey folder or a mission run folder)");
  }
  for (const char* file : {"textured/model.obj", "dense/fused.ply", "sparse/images.txt"}) {
    if (fs::is_regular_file(folder / file, ec)) return FolderKind::kSurvey;
  }
  for (const char* file : {"mission/map.bt", "mission/events.csv", "ground_truth/trajectory.tum"}) {
    if (fs::is_regular_file(folder / file, ec)) return FolderKind::kRun;
  }
  throw config::ConfigError(
      folder.string() +
      ": neither a survey (no textured/model.obj, dense/fused.ply or sparse/images.txt: "
      "`auv recon run` writes them) nor a mission run (no mission/map.bt, mission/events.csv "
      "or ground_truth/trajectory.tum: `auv launch bringup/launch/vehicle.yaml` writes them)");
}

}  // namespace auv::view
