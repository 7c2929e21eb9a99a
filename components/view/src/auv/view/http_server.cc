#include "auv/view/http_server.h"

#include <csignal>
#include <iostream>

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>

#include "auv/config/errors.h"

namespace auv::view {
namespace fs = std::filesystem;
namespace beast = boost::beast;
namespace http = beast::http;
namespace asio = boost::asio;
using tcp = asio::ip::tcp;

namespace {

std::string contentType(const fs::path& file) {
  const std::string ext = file.extension().string();
  if (ext == ".html") return "text/html; charset=utf-8";
  if (ext == ".js" || ext == ".mjs") return "text/javascript; charset=utf-8";
  if (ext == ".css") return "text/css; charset=utf-8";
  if (ext == ".json") return "application/json";
  if (ext == ".png") return "image/png";
  if (ext == ".jpg" || ext == ".jpeg") return "image/jpeg";
  return "application/octet-stream";
}

Response error(int status, const std::string& text) {
  Response r;
  r.status = status;
  r.body = text + "\n";
  return r;
}

}  // namespace

bool percentDecode(const std::string& in, std::string& out) {
  out.clear();
  for (size_t i = 0; i < in.size(); ++i) {
    if (in[i] != '%') {
      out += in[i];
      continue;
    }
    if (i + 2 >= in.size() || !std::isxdigit(static_cast<unsigned char>(in[i + 1])) ||
        !std::isxdigit(static_cast<unsigned char>(in[i + 2]))) {
      return false;
    }
    const char c = static_cast<char>(std::stoi(in.substr(i + 1, 2), nullptr, 16));
    if (c == '\0') return false;
    out += c;
    i += 2;
  }
  return true;
}

Router::Router(Scene scene, ServerOptions options)
    : scene_(std::move(scene)), options_(std::move(options)), port_(options_.port) {
  manifest_ = scene_.manifest.dump();
}

Response Router::staticFile(const fs::path& root, const std::string& relative) const {
  // Lexically first: no '..', '.', empty or hidden segment, no backslash; then the resolved
  // path (symbolic links followed) must still lie under the root.
  const fs::path rel(relative);
  if (relative.empty() || rel.is_absolute() || relative.find('\\') != std::string::npos) {
    return error(403, "forbidden path");
  }
  for (const auto& part : rel) {
    const std::string s = part.string();
    if (s.empty() || s[0] == '.') return error(403, "forbidden path");
  }
  std::error_code ec;
  const fs::path base = fs::canonical(root, ec);
  if (ec) return error(404, "not found");
  const fs::path file = fs::weakly_canonical(base / rel, ec);
  const fs::path inside = file.lexically_relative(base);
  if (ec || inside.empty() || *inside.begin() == "..") return error(403, "forbidden path");
  if (!fs::is_regular_file(file, ec)) return error(404, "not found");
  Response r;
  r.content_type = contentType(file);
  r.file = file;
  return r;
}

Response Router::route(const std::string& method, const std::string& target,
                       const std::string& host) const {
  if (method != "GET" && method != "HEAD") return error(405, "only GET and HEAD");
  const std::string port = std::to_string(port_);
  if (host != "127.0.0.1:" + port && host != "localhost:" + port && host != "[::1]:" + port &&
      host != options_.bind + ":" + port) {
    return error(403, "unexpected Host header '" + host + "' (the viewer answers its own address)");
  }
  std::string path;
  if (!percentDecode(target.substr(0, target.find('?')), path)) {
    return error(400, "malformed URL escape");
  }
  if (path.empty() || path[0] != '/') return error(400, "bad request target");
  if (path == "/" || path == "/index.html") return staticFile(options_.web_dir, "index.html");
  if (path == "/api/scene") {
    Response r;
    r.content_type = "application/json";
    r.blob = &manifest_;
    return r;
  }
  if (path.rfind("/data/", 0) == 0) {
    if (const auto it = scene_.blobs.find(path); it != scene_.blobs.end()) {
      Response r;
      r.content_type = it->second.content_type;
      r.blob = &it->second.bytes;
      return r;
    }
    if (const auto it = scene_.files.find(path); it != scene_.files.end()) {
      Response r;
      r.content_type = contentType(it->second);
      r.file = it->second;
      return r;
    }
    return error(404, "not found");
  }
  if (path.rfind("/app/", 0) == 0) return staticFile(options_.web_dir / "app", path.substr(5));
  if (path.rfind("/three/", 0) == 0) {
    const std::string rel = path.substr(7);
    // Only the ES modules: the package's other files are none of the page's business.
    if (rel.rfind("build/", 0) != 0 && rel.rfind("examples/jsm/", 0) != 0) {
      return error(404, "not found");
    }
    return staticFile(options_.three_dir, rel);
  }
  if (path == "/favicon.ico") return error(404, "not found");
  return error(404, "not found");
}

namespace {

class Session : public std::enable_shared_from_this<Session> {
 public:
  Session(tcp::socket socket, const Router& router) : stream_(std::move(socket)), router_(router) {}
  void start() { read(); }

 private:
  void read() {
    request_ = {};
    stream_.expires_after(std::chrono::seconds(60));
    http::async_read(stream_, buffer_, request_,
                     beast::bind_front_handler(&Session::onRead, shared_from_this()));
  }

  void onRead(beast::error_code ec, size_t) {
    if (ec) return close();
    const Response r =
        router_.route(std::string(request_.method_string()), std::string(request_.target()),
                      std::string(request_[http::field::host]));
    const bool head = request_.method() == http::verb::head;
    if (!r.file.empty()) {
      http::file_body::value_type body;
      beast::error_code open_error;
      body.open(r.file.c_str(), beast::file_mode::scan, open_error);
      if (open_error) return send(text(error(404, "not found")), head);
      http::response<http::file_body> res{http::status::ok, request_.version()};
      headers(res, r);
      res.body() = std::move(body);
      res.prepare_payload();
      return send(std::move(res), head);
    }
    if (r.blob) {
      http::response<http::span_body<const char>> res{static_cast<http::status>(r.status),
                                                      request_.version()};
      headers(res, r);
      res.body() = {r.blob->data(), r.blob->size()};
      res.prepare_payload();
      return send(std::move(res), head);
    }
    send(text(r), head);
  }

  http::response<http::string_body> text(const Response& r) {
    http::response<http::string_body> res{static_cast<http::status>(r.status), request_.version()};
    headers(res, r);
    res.body() = r.body;
    res.prepare_payload();
    return res;
  }

  template <class Res>
  void headers(Res& res, const Response& r) {
    res.set(http::field::server, "auv-view");
    res.set(http::field::content_type, r.content_type);
    res.set(http::field::cache_control, "no-store");
    res.set("X-Content-Type-Options", "nosniff");
    res.keep_alive(request_.keep_alive());
  }

  template <class Body>
  void send(http::response<Body>&& res, bool head) {
    if (head) {
      // Same headers, no body: the length is the one GET would send.
      http::response<http::empty_body> empty{res.result(), res.version()};
      for (const auto& field : res) empty.set(field.name_string(), field.value());
      empty.keep_alive(res.keep_alive());
      return write(std::make_shared<http::response<http::empty_body>>(std::move(empty)));
    }
    write(std::make_shared<http::response<Body>>(std::move(res)));
  }

  template <class Message>
  void write(std::shared_ptr<Message> message) {
    http::async_write(stream_, *message,
                      [self = shared_from_this(), message](beast::error_code ec, size_t) {
                        if (ec || !message->keep_alive()) return self->close();
                        self->read();
                      });
  }

  void close() {
    beast::error_code ignored;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
  }

  beast::tcp_stream stream_;
  beast::flat_buffer buffer_;
  http::request<http::string_body> request_;
  const Router& router_;
};

}  // namespace

struct HttpServer::Impl {
  Impl(Scene scene, const ServerOptions& options)
      : router(std::move(scene), options), acceptor(io), signals(io) {}
  void accept() {
    acceptor.async_accept([this](beast::error_code ec, tcp::socket socket) {
      if (!ec) std::make_shared<Session>(std::move(socket), router)->start();
      if (acceptor.is_open()) accept();
    });
  }
  Router router;
  asio::io_context io;
  tcp::acceptor acceptor;
  asio::signal_set signals;
};

HttpServer::HttpServer(Scene scene, const ServerOptions& options)
    : impl_(std::make_unique<Impl>(std::move(scene), options)) {
  beast::error_code ec;
  const auto address = asio::ip::make_address(options.bind, ec);
  if (ec) throw config::ConfigError("--bind: '" + options.bind + "' is not an IP address");
  const tcp::endpoint endpoint(address, options.port);
  auto& acceptor = impl_->acceptor;
  acceptor.open(endpoint.protocol(), ec);
  if (!ec) acceptor.set_option(asio::socket_base::reuse_address(true), ec);
  if (!ec) acceptor.bind(endpoint, ec);
  if (!ec) acceptor.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) {
    throw config::RuntimeFailure("cannot listen on " + options.bind + ":" +
                                 std::to_string(options.port) + ": " + ec.message() +
                                 (options.port ? " (try --port 0 for a free port)" : ""));
  }
  impl_->router.setPort(acceptor.local_endpoint().port());
}

HttpServer::~HttpServer() = default;

uint16_t HttpServer::port() const { return impl_->acceptor.local_endpoint().port(); }

void HttpServer::run(bool handle_signals) {
  if (handle_signals) {
    impl_->signals.add(SIGINT);
    impl_->signals.add(SIGTERM);
    impl_->signals.async_wait([this](beast::error_code, int) { stop(); });
  }
  impl_->accept();
  impl_->io.run();
}

void HttpServer::stop() {
  asio::post(impl_->io, [this] {
    beast::error_code ignored;
    impl_->acceptor.close(ignored);
    impl_->signals.cancel(ignored);
    impl_->io.stop();
  });
}

}  // namespace auv::view
