#pragma once
// The page's HTTP server (Boost.Beast): the page, three.js's ES modules, the scene manifest and
// its buffers. Loopback by default; every route maps to bytes in memory or to a file under
// the web folder, the three.js folder or one the scene names — never a path the client gives
// outside them (README.md, "Security").

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>

#include "auv/view/scene.h"

namespace auv::view {

struct ServerOptions {
  std::string bind = "127.0.0.1";
  uint16_t port = 8080;             ///< 0: a free port
  std::filesystem::path web_dir;    ///< index.html and app/
  std::filesystem::path three_dir;  ///< the npm package `three` (build/, examples/jsm/)
};

/// What a request gets, before it is written to the socket.
struct Response {
  int status = 200;
  std::string content_type = "text/plain; charset=utf-8";
  std::string body;                   ///< when neither blob nor file
  const std::string* blob = nullptr;  ///< bytes of the scene, not copied
  std::filesystem::path file;         ///< a file to stream
};

/// The route table alone (no sockets), so tests can call it directly. `host` is the request's
/// Host header: only the loopback names of the server's port are answered, so a web page of
/// another site cannot reach the viewer through DNS rebinding.
class Router {
 public:
  Router(Scene scene, ServerOptions options);
  Response route(const std::string& method, const std::string& target,
                 const std::string& host) const;
  void setPort(uint16_t port) { port_ = port; }
  const Scene& scene() const { return scene_; }

 private:
  Response staticFile(const std::filesystem::path& root, const std::string& relative) const;
  Scene scene_;
  ServerOptions options_;
  std::string manifest_;
  uint16_t port_ = 0;
};

/// Serves a Router on one thread. The constructor binds (so `port()` is known at once) and
/// throws config::RuntimeFailure naming the address when it cannot.
class HttpServer {
 public:
  HttpServer(Scene scene, const ServerOptions& options);
  ~HttpServer();
  uint16_t port() const;
  /// Serves until stop() or SIGINT/SIGTERM (when `handle_signals`).
  void run(bool handle_signals);
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Decodes %XX escapes; false for a malformed escape or a decoded NUL.
bool percentDecode(const std::string& in, std::string& out);

}  // namespace auv::view
