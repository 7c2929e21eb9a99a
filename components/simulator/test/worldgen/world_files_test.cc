// Writing worlds to disk, the world cache (ensureWorld) and `auv sim generate` as a user runs it.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "auv/sim/world/scenario.h"
#include "auv/sim/worldgen/generate_cli.h"
#include "auv/sim/worldgen/world_generator.h"

namespace auv::sim {
namespace {

namespace fs = std::filesystem;

class TempFolder {
 public:
  explicit TempFolder(const std::string& tag)
      : path_(fs::temp_directory_path() /
              ("auv_worldgen_files_" + tag + "_" + std::to_string(::getpid()))) {
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempFolder() { fs::remove_all(path_); }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

std::string readFile(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::ostringstream text;
  text << file.rdbuf();
  return text.str();
}

GeneratedWorld smallWorld(const std::string& name, uint64_t seed) {
  WorldGenOptions options;
  options.seed = seed;
  options.detail = 0.05;
  return generateWorld(name, options);
}

TEST(WriteWorldTest, WritesMeshTextureAndScenarioAndNothingElse) {
  TempFolder folder("write");
  const GeneratedWorld world = smallWorld("breakwater", 2);
  const std::string yaml = writeWorld(world, (folder.path() / "out").string());
  EXPECT_EQ(fs::path(yaml), folder.path() / "out" / "breakwater.yaml");
  bool has_obj = false, has_mtl = false, has_png = false;
  for (const auto& entry : fs::directory_iterator(folder.path() / "out")) {
    const std::string file = entry.path().filename().string();
    EXPECT_NE(file[0], '.') << "temporary left behind: " << file;
    has_obj |= file == "breakwater.obj";
    has_mtl |= file == "breakwater.mtl";
    has_png |= entry.path().extension() == ".png";
  }
  EXPECT_TRUE(has_obj && has_mtl && has_png);
  const Scenario scenario = loadScenario(yaml);
  EXPECT_EQ(scenario.name, "breakwater");
  EXPECT_EQ(scenario.up_axis, "z");
  EXPECT_NEAR(scenario.seabed_depth, 10.0, 1e-9);
  EXPECT_NEAR(scenario.water.visibility, world.visibility, 1e-9);
  EXPECT_TRUE(scenario.start_position.isApprox(world.start_position, 1e-3));
  ASSERT_EQ(scenario.queries.size(), world.queries.size());
  for (size_t i = 0; i < world.queries.size(); ++i) {
    EXPECT_EQ(scenario.queries[i].name, world.queries[i].name);
    EXPECT_TRUE(scenario.queries[i].goal.isApprox(world.queries[i].goal, 1e-3));
  }
}

TEST(WriteWorldTest, SameSeedGivesByteIdenticalFiles) {
  TempFolder folder("identical");
  writeWorld(smallWorld("canyon", 9), (folder.path() / "a").string());
  writeWorld(smallWorld("canyon", 9), (folder.path() / "b").string());
  for (const auto& entry : fs::directory_iterator(folder.path() / "a")) {
    const fs::path other = folder.path() / "b" / entry.path().filename();
    ASSERT_TRUE(fs::exists(other)) << other;
    EXPECT_TRUE(readFile(entry.path()) == readFile(other)) << entry.path().filename();
  }
}

TEST(EnsureWorldTest, ScenarioFilesPassThroughAndMissingOnesAreErrors) {
  TempFolder folder("passthrough");
  const fs::path yaml = folder.path() / "mine.yaml";
  std::ofstream(yaml) << "name: mine\n";
  EXPECT_EQ(ensureWorld(yaml.string(), 1, (folder.path() / "cache").string()), yaml.string());
  EXPECT_THROW(ensureWorld((folder.path() / "nope.yaml").string(), 1, folder.path().string()),
               ConfigError);
  try {
    ensureWorld("brekwater", 1, folder.path().string());
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("did you mean 'breakwater'"), std::string::npos);
  }
  EXPECT_FALSE(fs::exists(folder.path() / "cache"));
}

TEST(EnsureWorldTest, GeneratesOnceIntoTheCacheAndRebuildsStaleWorlds) {
  TempFolder folder("cache");
  const std::string cache = (folder.path() / "worlds").string();
  const std::string yaml = ensureWorld("breakwater", 12, cache, 0.05);
  EXPECT_EQ(fs::path(yaml), fs::path(cache) / "breakwater-12-d0.05" / "breakwater.yaml");
  ASSERT_TRUE(fs::is_regular_file(yaml));
  EXPECT_NO_THROW(loadWorldMesh(loadScenario(yaml)));

  // A second request uses the cached files as they are.
  const auto written = fs::last_write_time(yaml);
  std::ofstream(fs::path(yaml).parent_path() / "marker") << "kept";
  EXPECT_EQ(ensureWorld("breakwater", 12, cache, 0.05), yaml);
  EXPECT_EQ(fs::last_write_time(yaml), written);
  EXPECT_TRUE(fs::exists(fs::path(yaml).parent_path() / "marker"));

  // A world from another generator version is replaced.
  std::string text = readFile(yaml);
  text.replace(text.find(" v"), 3, " v0");
  std::ofstream(yaml, std::ios::trunc) << text;
  EXPECT_EQ(ensureWorld("breakwater", 12, cache, 0.05), yaml);
  EXPECT_FALSE(fs::exists(fs::path(yaml).parent_path() / "marker"));
  EXPECT_EQ(readFile(yaml).rfind(
                "# auv-inspect worldgen v" + std::to_string(kWorldGeneratorVersion) + ":", 0),
            0u);
  for (const auto& entry : fs::directory_iterator(cache))
    EXPECT_NE(entry.path().filename().string()[0], '.') << "temporary left behind";
}

TEST(EnsureWorldTest, DefaultCacheFollowsTheEnvironment) {
  const char* saved[3] = {std::getenv("AUV_WORLD_CACHE"), std::getenv("XDG_CACHE_HOME"),
                          std::getenv("HOME")};
  const std::string keep[3] = {saved[0] ? saved[0] : "", saved[1] ? saved[1] : "",
                               saved[2] ? saved[2] : ""};
  ::setenv("AUV_WORLD_CACHE", "/tmp/explicit", 1);
  EXPECT_EQ(defaultWorldCache(), "/tmp/explicit");
  ::unsetenv("AUV_WORLD_CACHE");
  ::setenv("XDG_CACHE_HOME", "/tmp/xdg", 1);
  EXPECT_EQ(defaultWorldCache(), "/tmp/xdg/auv-inspect/worlds");
  ::unsetenv("XDG_CACHE_HOME");
  ::setenv("HOME", "/home/someone", 1);
  EXPECT_EQ(defaultWorldCache(), "/home/someone/.cache/auv-inspect/worlds");
  const char* names[3] = {"AUV_WORLD_CACHE", "XDG_CACHE_HOME", "HOME"};
  for (int i = 0; i < 3; ++i) {
    if (saved[i])
      ::setenv(names[i], keep[i].c_str(), 1);
    else
      ::unsetenv(names[i]);
  }
}

int run(const std::vector<std::string>& args, std::string& out, std::string& err) {
  std::ostringstream o, e;
  const int code = runGenerateCommand(args, o, e);
  out = o.str();
  err = e.str();
  return code;
}

TEST(GenerateCommandTest, HelpListAndUsageErrors) {
  std::string out, err;
  EXPECT_EQ(run({"--help"}, out, err), 0);
  EXPECT_NE(out.find("usage: auv sim generate"), std::string::npos);
  EXPECT_NE(out.find("dead_end_bay"), std::string::npos);
  EXPECT_EQ(run({"--list"}, out, err), 0);
  EXPECT_NE(out.find("canyon"), std::string::npos);

  const std::vector<std::vector<std::string>> bad = {{},
                                                     {"canyon", "--seed", "-3"},
                                                     {"canyon", "--seed"},
                                                     {"canyon", "--detail", "lots"},
                                                     {"canyon", "--detail", "100"},
                                                     {"canyon", "--texture-size", "12"},
                                                     {"canyon", "--frobnicate"},
                                                     {"canyon", "breakwater"},
                                                     {"canyno"}};
  for (const auto& args : bad) {
    EXPECT_EQ(run(args, out, err), 2) << ::testing::PrintToString(args);
    EXPECT_EQ(err.rfind("auv sim generate: ", 0), 0u) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << "one line: " << err;
  }
  run({"canyno"}, out, err);
  EXPECT_NE(err.find("did you mean 'canyon'"), std::string::npos) << err;
}

TEST(GenerateCommandTest, WritesTheWorldAndSaysWhatItWrote) {
  TempFolder folder("cli");
  std::string out, err;
  const fs::path dir = folder.path() / "worlds";
  ASSERT_EQ(run({"breakwater", "--seed", "4", "--detail", "0.05", "--out", dir.string()}, out, err),
            0)
      << err;
  EXPECT_TRUE(err.empty()) << err;
  EXPECT_NE(out.find("breakwater: "), std::string::npos) << out;
  EXPECT_NE(out.find(" triangles, texture "), std::string::npos) << out;
  EXPECT_NE(out.find((dir / "breakwater.yaml").string()), std::string::npos) << out;
  EXPECT_TRUE(fs::is_regular_file(dir / "breakwater.obj"));
  EXPECT_NE(readFile(dir / "breakwater.yaml").find("seed 4"), std::string::npos);

  // An output path that cannot be a folder is a runtime failure (exit 1), not a usage error.
  std::ofstream(folder.path() / "file") << "x";
  EXPECT_EQ(
      run({"breakwater", "--detail", "0.05", "--out", (folder.path() / "file").string()}, out, err),
      1);
  EXPECT_EQ(err.rfind("auv sim generate: breakwater: ", 0), 0u) << err;
}

}  // namespace
}  // namespace auv::sim
