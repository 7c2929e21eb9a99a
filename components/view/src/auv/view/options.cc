#include "auv/view/options.h"

#include <cstdlib>

#include "auv/config/errors.h"
#include "auv/view/folder.h"

namespace auv::view {
namespace fs = std::filesystem;

const char* const kUsage =
    "usage: auv view <survey-or-run-folder> [options]\n"
    "       auv view --live [ws://host:port] [<run-folder>] [options]\n"
    "Serves a 3-D view of the folder on this machine and prints its URL.\n"
    "  --port N              port to listen on (default 8080; 0: a free one)\n"
    "  --bind ADDR           address to listen on (default 127.0.0.1; anything else exposes\n"
    "                        the data, unauthenticated, to the network)\n"
    "  --live [URL]          follow a running mission through a Foxglove WebSocket bridge\n"
    "                        (default ws://127.0.0.1:8765)\n"
    "  --max-triangles N     the finest model level the page picks by itself has at most\n"
    "                        N triangles (default 300000; every level can be chosen in it)\n"
    "  --max-points N        clouds thinned to at most N points (default 1000000)\n"
    "Exit codes: 0 stopped (Ctrl-C), 1 could not serve, 2 bad options or folder.\n";

namespace {

size_t positive(const std::string& option, const std::string& text, size_t max) {
  size_t used = 0;
  unsigned long long value = 0;
  try {
    value = std::stoull(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || text.empty() || text[0] == '-' || value > max) {
    throw config::ConfigError(option + ": expected an integer in [0, " + std::to_string(max) +
                              "], got '" + text + "'");
  }
  return static_cast<size_t>(value);
}

}  // namespace

ViewOptions parseOptions(const std::vector<std::string>& args) {
  ViewOptions o;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto value = [&]() -> const std::string& {
      if (i + 1 >= args.size()) throw config::ConfigError(a + ": needs a value");
      return args[++i];
    };
    if (a == "-h" || a == "--help") {
      o.help = true;
    } else if (a == "--port") {
      o.server.port = static_cast<uint16_t>(positive(a, value(), 65535));
    } else if (a == "--bind") {
      o.server.bind = value();
    } else if (a == "--max-triangles") {
      o.scene.default_triangles = std::max<size_t>(positive(a, value(), 1u << 31), 1);
    } else if (a == "--max-points") {
      o.scene.max_points = std::max<size_t>(positive(a, value(), 1u << 31), 1);
    } else if (a == "--live") {
      o.live = "ws://127.0.0.1:8765";
      if (i + 1 < args.size() && args[i + 1].find("://") != std::string::npos) {
        o.live = args[++i];
        if (o.live.rfind("ws://", 0) != 0 && o.live.rfind("wss://", 0) != 0) {
          throw config::ConfigError("--live: expected a ws:// or wss:// URL, got '" + o.live + "'");
        }
      }
    } else if (!a.empty() && a[0] == '-') {
      throw config::ConfigError("unknown option '" + a + "'");
    } else if (o.folder.empty()) {
      o.folder = a;
    } else {
      throw config::ConfigError("one folder at a time ('" + o.folder.string() + "' and '" + a +
                                "')");
    }
  }
  if (!o.help && o.folder.empty() && o.live.empty()) {
    throw config::ConfigError("no folder given (a survey or a mission run folder, or --live)");
  }
  return o;
}

Scene buildScene(const ViewOptions& options) {
  Scene scene;
  if (!options.folder.empty()) {
    const FolderKind kind = detectFolder(options.folder);
    if (kind == FolderKind::kRun) {
      scene = buildRunScene(options.folder, options.scene);
    } else {
      scene = buildSurveyScene(options.folder, options.scene);
    }
  } else {
    scene.manifest = {{"kind", "live"},
                      {"name", "live"},
                      {"frame", "world (NED: x north, y east, z down)"},
                      {"layers", nlohmann::json::array()},
                      {"notes", nlohmann::json::array()}};
  }
  if (!options.live.empty()) scene.manifest["live"] = options.live;
  return scene;
}

fs::path findWebDir(const fs::path& executable) {
  const fs::path installed = executable.parent_path().parent_path() / "share/auv_view/web";
  if (fs::is_regular_file(installed / "index.html")) return installed;
  const fs::path source = AUV_VIEW_SOURCE_WEB;
  if (fs::is_regular_file(source / "index.html")) return source;
  throw config::RuntimeFailure("the page is missing: neither " + installed.string() + " nor " +
                               source.string() + " holds index.html (rebuild auv_view)");
}

fs::path findThreeDir(const fs::path& executable) {
  std::vector<fs::path> places;
  if (const char* env = std::getenv("AUV_VIEW_THREE_DIR")) places.emplace_back(env);
  places.push_back(executable.parent_path().parent_path() / "share/auv_view/three");
  places.emplace_back(AUV_VIEW_SOURCE_THREE);
  std::string looked;
  for (const auto& p : places) {
    if (fs::is_regular_file(p / "build/three.module.js")) return p;
    looked += (looked.empty() ? "" : ", ") + p.string();
  }
  throw config::RuntimeFailure("three.js is missing (looked in " + looked +
                               "): run scripts/install-deps.sh (npm ci in js/), then rebuild");
}

}  // namespace auv::view
