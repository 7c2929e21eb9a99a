#pragma once
// `auv view` options (README.md, "Options") and what they turn into.

#include <filesystem>
#include <string>
#include <vector>

#include "auv/view/http_server.h"
#include "auv/view/scene.h"

namespace auv::view {

extern const char* const kUsage;

struct ViewOptions {
  std::filesystem::path folder;  ///< survey or run; may be empty with --live
  std::string live;              ///< Foxglove WebSocket URL; empty: not live
  ServerOptions server;
  SceneOptions scene;
  bool help = false;
};

/// Throws config::ConfigError naming the option and the value.
ViewOptions parseOptions(const std::vector<std::string>& args);

/// The folder's scene (detectFolder: ConfigError, exit 2, for one of neither kind), with
/// manifest["live"] when live.
Scene buildScene(const ViewOptions& options);

/// The page (share/auv_view/web next to the program, else this package's source) and three.js
/// (AUV_VIEW_THREE_DIR, share/auv_view/three, else the workspace's js/node_modules/three).
/// Throws config::RuntimeFailure naming the places looked at and the step that installs it.
std::filesystem::path findWebDir(const std::filesystem::path& executable);
std::filesystem::path findThreeDir(const std::filesystem::path& executable);

}  // namespace auv::view
