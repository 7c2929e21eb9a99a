// The HTTP server: routes, refusal of every way out of the served folders, Host and method
// checks, and the same over a real socket (Boost.Beast client).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <thread>

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>

#include "auv/config/errors.h"
#include "auv/view/http_server.h"

namespace auv::view {
namespace {
namespace fs = std::filesystem;
namespace http = boost::beast::http;
using tcp = boost::asio::ip::tcp;

class ServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() /
            ("auv_view_server_" + std::to_string(::getpid()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    fs::create_directories(root_ / "web" / "app");
    fs::create_directories(root_ / "three" / "build");
    fs::create_directories(root_ / "data");
    std::ofstream(root_ / "web" / "index.html") << "<!doctype html>page";
    std::ofstream(root_ / "web" / "app" / "main.js") << "export {};";
    std::ofstream(root_ / "web" / "app" / ".hidden") << "hidden";
    std::ofstream(root_ / "three" / "build" / "three.module.js") << "// three";
    std::ofstream(root_ / "three" / "package.json") << "{}";
    std::ofstream(root_ / "secret.txt") << "SECRET";
    std::ofstream(root_ / "data" / "texture.png") << "PNG";
    fs::create_symlink(root_ / "secret.txt", root_ / "web" / "app" / "link.js");
    options_.web_dir = root_ / "web";
    options_.three_dir = root_ / "three";
    options_.port = 0;
    scene_.manifest = {{"kind", "survey"}, {"layers", nlohmann::json::array()}};
    scene_.blobs["/data/model_0.bin"] = Blob{"application/octet-stream", "BYTES"};
    scene_.addFile(root_ / "data" / "texture.png");
  }
  void TearDown() override { fs::remove_all(root_); }

  Response get(const Router& router, const std::string& target,
               const std::string& host = "127.0.0.1:8080") {
    return router.route("GET", target, host);
  }

  fs::path root_;
  ServerOptions options_;
  Scene scene_;
};

TEST_F(ServerTest, Routes) {
  Router router(scene_, options_);
  router.setPort(8080);
  Response r = get(router, "/");
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.file.filename(), "index.html");
  EXPECT_EQ(r.content_type, "text/html; charset=utf-8");
  r = get(router, "/api/scene");
  ASSERT_NE(r.blob, nullptr);
  EXPECT_EQ(nlohmann::json::parse(*r.blob)["kind"], "survey");
  r = get(router, "/data/model_0.bin?x=1");
  ASSERT_NE(r.blob, nullptr);
  EXPECT_EQ(*r.blob, "BYTES");
  r = get(router, "/data/file/0.png");
  EXPECT_EQ(r.file, root_ / "data" / "texture.png");
  EXPECT_EQ(r.content_type, "image/png");
  r = get(router, "/app/main.js");
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.content_type, "text/javascript; charset=utf-8");
  EXPECT_EQ(get(router, "/three/build/three.module.js").status, 200);
  // Only build/ and examples/jsm/ of the three package; nothing else anywhere.
  EXPECT_EQ(get(router, "/three/package.json").status, 404);
  EXPECT_EQ(get(router, "/data/file/1.png").status, 404);
  EXPECT_EQ(get(router, "/nothing").status, 404);
  EXPECT_EQ(get(router, "/app/missing.js").status, 404);
}

TEST_F(ServerTest, RefusesEveryWayOutOfItsFolders) {
  Router router(scene_, options_);
  router.setPort(8080);
  for (const std::string target :
       {"/app/../secret.txt", "/app/../../secret.txt", "/app/%2e%2e/secret.txt",
        "/app/..%2fsecret.txt", "/app/%2E%2E%2F%2E%2E%2Fsecret.txt",
        "/three/build/../../secret.txt", "/three/build/%2e%2e/%2e%2e/secret.txt", "/app/link.js",
        "/app/.hidden", "/app//etc/passwd", "/app/%2fetc%2fpasswd", "/app/..\\secret.txt",
        "/three/examples/jsm/../../../secret.txt"}) {
    const Response r = get(router, target);
    EXPECT_TRUE(r.status == 403 || r.status == 404) << target << " -> " << r.status;
    EXPECT_NE(r.file, root_ / "secret.txt") << target;
    EXPECT_TRUE(r.file.empty()) << target << " served " << r.file;
  }
  EXPECT_EQ(get(router, "/app/%00").status, 400);
  EXPECT_EQ(get(router, "/app/%zz").status, 400);
  EXPECT_EQ(get(router, "/data/../app/main.js").status, 404);  // data routes are exact names
}

TEST_F(ServerTest, AnswersOnlyItsOwnHostAndGetOrHead) {
  Router router(scene_, options_);
  router.setPort(8080);
  EXPECT_EQ(get(router, "/", "localhost:8080").status, 200);
  EXPECT_EQ(get(router, "/", "[::1]:8080").status, 200);
  // DNS rebinding: a page of evil.example resolved to 127.0.0.1 sends its own Host.
  const Response r = get(router, "/api/scene", "evil.example:8080");
  EXPECT_EQ(r.status, 403);
  EXPECT_NE(r.body.find("evil.example"), std::string::npos);
  EXPECT_EQ(get(router, "/", "127.0.0.1:9999").status, 403);
  EXPECT_EQ(router.route("POST", "/api/scene", "127.0.0.1:8080").status, 405);
  EXPECT_EQ(router.route("HEAD", "/", "127.0.0.1:8080").status, 200);
}

/// One request over a new connection: status and body.
std::pair<int, std::string> fetch(uint16_t port, const std::string& target,
                                  http::verb verb = http::verb::get, size_t* length = nullptr) {
  boost::asio::io_context io;
  tcp::resolver resolver(io);
  boost::beast::tcp_stream stream(io);
  stream.connect(resolver.resolve("127.0.0.1", std::to_string(port)));
  http::request<http::empty_body> req{verb, target, 11};
  req.set(http::field::host, "127.0.0.1:" + std::to_string(port));
  http::write(stream, req);
  boost::beast::flat_buffer buffer;
  http::response_parser<http::string_body> parser;
  parser.skip(verb == http::verb::head);
  http::read(stream, buffer, parser);
  if (length)
    *length = parser.get().has_content_length()
                  ? std::stoul(std::string(parser.get()[http::field::content_length]))
                  : 0;
  return {static_cast<int>(parser.get().result_int()), parser.get().body()};
}

TEST_F(ServerTest, ServesOverASocketOnLoopback) {
  HttpServer server(scene_, options_);
  const uint16_t port = server.port();
  EXPECT_NE(port, 0);
  std::thread thread([&] { server.run(false); });
  EXPECT_EQ(fetch(port, "/"), std::make_pair(200, std::string("<!doctype html>page")));
  EXPECT_EQ(fetch(port, "/data/model_0.bin"), std::make_pair(200, std::string("BYTES")));
  EXPECT_EQ(fetch(port, "/data/file/0.png").second, "PNG");
  const auto refused = fetch(port, "/app/../../secret.txt");
  EXPECT_EQ(refused.first, 403);
  EXPECT_EQ(refused.second.find("SECRET"), std::string::npos);
  size_t length = 0;
  const auto head = fetch(port, "/", http::verb::head, &length);
  EXPECT_EQ(head.first, 200);
  EXPECT_EQ(length, std::string("<!doctype html>page").size());
  EXPECT_TRUE(head.second.empty());
  server.stop();
  thread.join();
}

TEST_F(ServerTest, ABusyPortOrABadAddressIsNamed) {
  HttpServer first(scene_, options_);
  ServerOptions same = options_;
  same.port = first.port();
  try {
    HttpServer second(scene_, same);
    FAIL() << "bound a port already in use";
  } catch (const config::RuntimeFailure& e) {
    EXPECT_NE(std::string(e.what()).find(std::to_string(same.port)), std::string::npos) << e.what();
  }
  ServerOptions bad = options_;
  bad.bind = "not-an-address";
  EXPECT_THROW(HttpServer(scene_, bad), config::ConfigError);
}

TEST(PercentDecode, DecodesAndRefusesNul) {
  std::string out;
  EXPECT_TRUE(percentDecode("/a%20b%2F", out));
  EXPECT_EQ(out, "/a b/");
  EXPECT_FALSE(percentDecode("/a%00", out));
  EXPECT_FALSE(percentDecode("/a%2", out));
}

}  // namespace
}  // namespace auv::view
