// The page in headless Chromium (Debian's /usr/bin/chromium, software GL) driven by
// puppeteer-core (js/node_modules): a demo survey, a demo run and live mode fed by a Foxglove
// WebSocket server — @foxglove/ws-protocol's own — load without console errors, draw pixels and
// report the expected object counts (test/js/view_check.mjs prints what the page reports).
// Skipped with the step that installs what is missing.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>

#include <boost/asio/ip/tcp.hpp>
#include <nlohmann/json.hpp>

#include "child.h"
#include "fixtures.h"

namespace auv::view {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

const fs::path kJsDir = AUV_VIEW_JS_DIR;
const fs::path kScripts = AUV_VIEW_TEST_JS;

std::string chromium() {
  const char* env = std::getenv("AUV_VIEW_CHROMIUM");
  return env ? env : "/usr/bin/chromium";
}

/// Why the browser tests cannot run here, or "".
std::string missing() {
  if (std::system("command -v node >/dev/null 2>&1") != 0) {
    return "node is not installed (scripts/install-deps.sh installs it)";
  }
  for (const char* module : {"puppeteer-core", "three", "@foxglove/ws-protocol", "ws"}) {
    if (!fs::exists(kJsDir / "node_modules" / module)) {
      return (kJsDir / "node_modules" / module).string() +
             " is missing (scripts/install-deps.sh runs npm ci in js/)";
    }
  }
  if (!fs::exists(chromium())) {
    return chromium() + " is missing (apt-get install chromium; scripts/install-deps.sh)";
  }
  return "";
}

fs::path tempDir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("auv_view_browser_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

/// auv-view with `args` on a free port; its URL, or "" when it did not start.
std::string startView(test::Child& view) {
  const std::string line = view.waitFor("open http://", 120);
  const size_t start = line.find("http://");
  if (start == std::string::npos) return "";
  return line.substr(start, line.find(' ', start) - start);
}

std::vector<std::string> checkCommand(const std::string& url,
                                      const std::vector<std::string>& extra) {
  std::vector<std::string> argv = {"node", (kScripts / "view_check.mjs").string(), url, chromium()};
  argv.insert(argv.end(), extra.begin(), extra.end());
  return argv;
}

/// view_check.mjs's JSON line (it prints one at the end).
json checkResult(test::Child& node) {
  std::string line, last;
  while (node.readLine(line, 240)) last = line;
  node.wait();
  try {
    return json::parse(last);
  } catch (const std::exception& e) {
    ADD_FAILURE() << "view_check.mjs printed no JSON: '" << last << "'";
    return json::object();
  }
}

json check(const std::string& url, const std::vector<std::string>& extra = {}) {
  test::Child node(checkCommand(url, extra));
  return checkResult(node);
}

/// No console error, failed request or HTTP error; at least `drawn` of the canvas not background.
void expectCleanPage(const json& result, double drawn = 0.01) {
  EXPECT_EQ(result.value("errors", json::array()), json::array()) << result.dump();
  EXPECT_EQ(result.value("requestsFailed", json::array()), json::array()) << result.dump();
  EXPECT_GT(result.value("nonBackground", 0.0), drawn) << "blank canvas: " << result.dump();
}

TEST(Browser, ShowsASurvey) {
  const std::string why = missing();
  if (!why.empty()) GTEST_SKIP() << why;
  const fs::path survey = tempDir("survey");
  const auto counts = test::writeDemoSurvey(survey);
  test::Child view({AUV_VIEW_EXE, survey.string(), "--port", "0"});
  const std::string url = startView(view);
  ASSERT_FALSE(url.empty());
  const json result = check(url, {"--delay-textures-ms", "2000"});
  expectCleanPage(result);
  // The atlas drawn, not a black model: the page renders again when a texture arrives.
  EXPECT_TRUE(result.value("drawnAfterTextures", false)) << result.dump();
  EXPECT_GT(result.value("lit", 0.0), 0.05) << result.dump();
  const json& c = result["view"]["counts"];
  EXPECT_EQ(result["view"]["kind"], "survey");
  EXPECT_EQ(c.value("model", 0u), counts.triangles) << c.dump();
  EXPECT_EQ(c.value("dense", 0u), counts.dense_points) << c.dump();
  EXPECT_EQ(c.value("sparse", 0u), counts.sparse_points) << c.dump();
  EXPECT_EQ(c.value("cameras", 0u), counts.cameras) << c.dump();
  EXPECT_EQ(c.value("contribution", 0u), counts.dense_points) << c.dump();
  EXPECT_EQ(c.value("trajectory_sfm", 0u), 2u) << c.dump();
  EXPECT_EQ(c.value("trajectory_estimated", 0u), 1u) << c.dump();
  EXPECT_EQ(c.value("trajectory_true", 0u), 1u) << c.dump();
  fs::remove_all(survey);
}

TEST(Browser, ShowsAMissionRun) {
  const std::string why = missing();
  if (!why.empty()) GTEST_SKIP() << why;
  const fs::path run = tempDir("run");
  const auto counts = test::writeDemoRun(run);
  test::Child view({AUV_VIEW_EXE, run.string(), "--port", "0"});
  const std::string url = startView(view);
  ASSERT_FALSE(url.empty());
  const json result = check(url);
  expectCleanPage(result);
  const json& c = result["view"]["counts"];
  EXPECT_EQ(result["view"]["kind"], "run");
  EXPECT_EQ(c.value("map", 0u), counts.voxels) << c.dump();
  EXPECT_EQ(c.value("trees", 0u), counts.tree_edges) << c.dump();
  EXPECT_EQ(c.value("paths", 0u), counts.paths) << c.dump();
  EXPECT_EQ(c.value("waypoints", 0u), counts.waypoints) << c.dump();
  EXPECT_EQ(c.value("collisions", 0u), counts.collisions) << c.dump();
  EXPECT_EQ(c.value("trajectory_true", 0u), 1u) << c.dump();
  EXPECT_EQ(c.value("trajectory_estimated", 0u), 1u) << c.dump();
  fs::remove_all(run);
}

/// With one texture grid over the terrain (levels keep the atlas) and with a patch per face, as
/// `auv recon texture` writes (coarse levels coloured per vertex).
class BrowserLevels : public ::testing::TestWithParam<bool> {};

TEST_P(BrowserLevels, ModelLevelFollowsTheView) {
  const std::string why = missing();
  if (!why.empty()) GTEST_SKIP() << why;
  const fs::path survey = tempDir("levels");
  test::writeTerrainSurvey(survey, 200000, 1, /*patch_per_face=*/GetParam());
  test::Child view({AUV_VIEW_EXE, survey.string(), "--port", "0"});
  const std::string url = startView(view);
  ASSERT_FALSE(url.empty());
  const json result = check(url, {"--zoom", "8"});
  expectCleanPage(result);
  // Whole model in view: a coarse level; 8 times closer: a finer one (a lower index) with more
  // triangles; back out: the coarse one again.
  const int before = result.value("levelBeforeZoom", -1),
            after = result.value("levelAfterZoom", -1);
  EXPECT_GT(before, 0) << result.dump();
  EXPECT_LT(after, before) << result.dump();
  EXPECT_GT(result.value("trianglesAfterZoom", 0), result.value("trianglesBeforeZoom", 0))
      << result.dump();
  EXPECT_EQ(result.value("levelAfterZoomOut", -1), before) << result.dump();
  EXPECT_GT(result.value("lit", 0.0), 0.05) << "a dark model: " << result.dump();
  fs::remove_all(survey);
}

INSTANTIATE_TEST_SUITE_P(Atlas, BrowserLevels, ::testing::Values(false, true),
                         [](const auto& info) { return info.param ? "PatchPerFace" : "Grid"; });

/// What the live view saw from a bridge at `ws`, over `seconds` of watching: the vehicle moved,
/// and the `expected` entities arrived with lines or cubes (`entities`: what was seen).
void expectLiveVehicleMoves(const std::string& ws, double seconds, json& entities,
                            const std::vector<std::string>& expected = {"map", "tree", "path",
                                                                        "trajectory_true",
                                                                        "trajectory_estimated",
                                                                        "vehicle"},
                            double drawn = 0.01) {
  test::Child view({AUV_VIEW_EXE, "--live", ws, "--port", "0"});
  const std::string url = startView(view);
  ASSERT_FALSE(url.empty());
  const json result = check(url, {"--live-seconds", std::to_string(seconds)});
  expectCleanPage(result, drawn);
  ASSERT_TRUE(result.contains("view")) << result.dump();
  const json& live = result["view"]["live"];
  EXPECT_TRUE(live.value("connected", false)) << result.dump();
  ASSERT_TRUE(result.contains("vehicleFirst") && result.contains("vehicleLast")) << result.dump();
  const json &a = result["vehicleFirst"], &b = result["vehicleLast"];
  const double moved = std::hypot(b["x"].get<double>() - a["x"].get<double>(),
                                  b["y"].get<double>() - a["y"].get<double>());
  EXPECT_GT(moved, 0.2) << result.dump();
  EXPECT_GT(b["updates"].get<int>(), a["updates"].get<int>() + 5) << result.dump();
  entities = live["entities"];
  for (const std::string& id : expected) {
    const json& e = entities[id];
    EXPECT_GT(e.value("lines", 0) + e.value("cubes", 0), 0) << id << ": " << entities.dump();
  }
}

TEST(Browser, LiveModeSeesTheVehicleMove) {
  const std::string why = missing();
  if (!why.empty()) GTEST_SKIP() << why;
  test::Child bridge({"node", (kScripts / "fake_bridge.mjs").string()});
  std::string line;
  ASSERT_TRUE(bridge.readLine(line, 60)) << "fake_bridge.mjs did not start";
  const int port = json::parse(line)["port"];
  json entities;
  expectLiveVehicleMoves("ws://127.0.0.1:" + std::to_string(port), 2.0, entities);
  // What fake_bridge.mjs sends: a 12 x 5 wall of cubes, a two-edge tree (LINE_LIST).
  EXPECT_EQ(entities["map"].value("cubes", 0), 60) << entities.dump();
  EXPECT_EQ(entities["tree"].value("segments", 0), 2) << entities.dump();
}

TEST(Browser, LiveModeWaitsForABridgeThatComesLater) {
  const std::string why = missing();
  if (!why.empty()) GTEST_SKIP() << why;
  int port = 0;
  {  // a free port for the bridge to come
    boost::asio::io_context io;
    boost::asio::ip::tcp::acceptor probe(
        io, boost::asio::ip::tcp::endpoint(boost::asio::ip::make_address("127.0.0.1"), 0));
    port = probe.local_endpoint().port();
  }
  const std::string ws = "ws://127.0.0.1:" + std::to_string(port);
  test::Child view({AUV_VIEW_EXE, "--live", ws, "--port", "0"});
  const std::string url = startView(view);
  ASSERT_FALSE(url.empty());
  test::Child page(checkCommand(url, {"--live-seconds", "2"}));
  ::sleep(5);  // the page is up, tries and fails to connect, retries every 2 s
  test::Child bridge({"node", (kScripts / "fake_bridge.mjs").string(), std::to_string(port)});
  std::string line;
  ASSERT_TRUE(bridge.readLine(line, 60)) << "fake_bridge.mjs did not start";
  json result = checkResult(page);
  // Chromium logs each refused connection; that is the expected part of this test.
  json errors = json::array();
  for (const auto& e : result.value("errors", json::array())) {
    if (e.get<std::string>().find("WebSocket connection to '" + ws) == std::string::npos) {
      errors.push_back(e);
    }
  }
  result["errors"] = errors;
  expectCleanPage(result);
  ASSERT_TRUE(result.contains("vehicleLast")) << result.dump();
  EXPECT_GT(result["vehicleLast"]["updates"].get<int>(), 5) << result.dump();
  EXPECT_GE(result["view"]["live"].value("connections", 0), 1) << result.dump();
}

/// The real bridge (components/foxglove_bridge, `auv run foxglove_bridge`) on DDS domain 27, fed
/// odometry by `auv topic pub` moving 1 m every half second: the page follows /tf and the
/// vehicle entities it publishes. Skipped when the bridge component is not installed.
TEST(Browser, LiveModeWithTheFoxgloveBridge) {
  const std::string why = missing();
  if (!why.empty()) GTEST_SKIP() << why;
  {
    test::Child list({"sh", "-c", "auv run --list 2>&1"});
    std::string line, all;
    while (list.readLine(line, 60)) all += line + "\n";
    if (list.wait() != 0 || all.find("foxglove_bridge") == std::string::npos) {
      GTEST_SKIP() << "`auv run --list` (install/setup.bash sourced) has no foxglove_bridge";
    }
  }
  ::setenv("AUV_DOMAIN_ID", "27", 1);  // the children's domain (test/README.md)
  test::Child bridge({"sh", "-c", "exec auv run foxglove_bridge -p port:=0 2>&1"});
  const std::string line = bridge.waitFor("Foxglove WebSocket server on ws://", 60);
  const size_t start = line.find("ws://");
  ASSERT_NE(start, std::string::npos) << "the bridge did not start";
  const std::string ws = line.substr(start, line.find_first_of(" ,", start) - start);
  // One `auv topic pub` per position (state QoS, as the bridge's odometry reader asks).
  test::Child odometry(
      {"sh", "-c",
       "for i in $(seq 120); do auv topic pub nav/odometry Odometry \"{pose: {pose: {position: "
       "{x: $i, y: 1, z: 2}, orientation: {w: 1}}}}\" --times 5 --rate 10 --qos state "
       ">/dev/null 2>&1; done"});
  json entities;
  // A vehicle and a short line only: a small share of the canvas.
  expectLiveVehicleMoves(ws, 3.0, entities, {"vehicle", "trajectory_estimated"}, 0.001);
  ::unsetenv("AUV_DOMAIN_ID");
}

}  // namespace
}  // namespace auv::view
