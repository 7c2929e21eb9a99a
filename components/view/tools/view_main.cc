// `auv view <folder>` (run by `auv` as auv-view): converts a survey or a mission run folder
// into what the page draws, serves the page on loopback and prints its URL (README.md).
#include <chrono>
#include <filesystem>
#include <iostream>

#include "auv/config/errors.h"
#include "auv/view/http_server.h"
#include "auv/view/options.h"

int main(int argc, char** argv) {
  namespace view = auv::view;
  try {
    view::ViewOptions options = view::parseOptions(std::vector<std::string>(argv + 1, argv + argc));
    if (options.help) {
      std::cout << view::kUsage;
      return 0;
    }
    std::error_code ec;
    auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
    if (ec) self = argv[0];
    options.server.web_dir = view::findWebDir(self);
    options.server.three_dir = view::findThreeDir(self);
    const auto start = std::chrono::steady_clock::now();
    view::Scene scene = view::buildScene(options);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const std::string kind = scene.manifest.value("kind", "");
    for (const auto& note : scene.manifest["notes"]) {
      std::cerr << "auv view: note: " << note.get<std::string>() << "\n";
    }
    view::HttpServer server(std::move(scene), options.server);
    const std::string host = options.server.bind.find(':') != std::string::npos
                                 ? "[" + options.server.bind + "]"
                                 : options.server.bind;
    if (options.server.bind != "127.0.0.1" && options.server.bind != "::1") {
      std::cerr << "auv view: warning: listening on " << options.server.bind
                << ": anyone who can reach it sees the data (no authentication)\n";
    }
    std::cout << "auv view: " << kind
              << (options.folder.empty() ? "" : " " + options.folder.string()) << " prepared in "
              << static_cast<int>(seconds * 1000) << " ms\n"
              << "auv view: open http://" << host << ":" << server.port() << "/  (Ctrl-C stops)"
              << std::endl;
    server.run(true);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "auv view: " << e.what() << "\n";
    if (auv::config::exitCodeFor(e) == 2) std::cerr << auv::view::kUsage;
    return auv::config::exitCodeFor(e);
  }
}
