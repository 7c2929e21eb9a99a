// Where `auv run` looks for component libraries (componentSearchPath): the environment's
// folders, the running install's own, and the other packages' prefixes only in an isolated
// colcon install (a merged install's neighbours, e.g. an older copy of it, must not load). No DDS.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

#include "auv/interfaces/component.h"

namespace auv::interfaces {
namespace {

namespace fs = std::filesystem;

/// Sets (or unsets) an environment variable for the test's lifetime.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    if (value != nullptr)
      ::setenv(name, value, 1);
    else
      ::unsetenv(name);
  }
  ~ScopedEnv() {
    if (old_)
      ::setenv(name_, old_->c_str(), 1);
    else
      ::unsetenv(name_);
  }

 private:
  const char* name_;
  std::optional<std::string> old_;
};

class ComponentSearchPathTest : public testing::Test {
 protected:
  ComponentSearchPathTest()
      : root_(fs::temp_directory_path() /
              ("auv_component_path_" +
               std::to_string(std::chrono::steady_clock::now().time_since_epoch().count()))),
        no_component_path_("AUV_COMPONENT_PATH", nullptr),
        no_prefix_path_("CMAKE_PREFIX_PATH", nullptr) {}
  ~ComponentSearchPathTest() override {
    std::error_code ignored;
    fs::remove_all(root_, ignored);
  }
  /// An install folder with a layout file and the given package prefixes' component folders.
  void makeInstall(const fs::path& install, const std::string& layout) {
    fs::create_directories(install);
    std::ofstream(install / ".colcon_install_layout") << layout << "\n";
  }
  static bool contains(const std::vector<fs::path>& dirs, const fs::path& dir) {
    return std::find(dirs.begin(), dirs.end(), dir) != dirs.end();
  }

  fs::path root_;
  ScopedEnv no_component_path_;
  ScopedEnv no_prefix_path_;
};

TEST_F(ComponentSearchPathTest, MergedInstallLooksInItsOwnPrefixOnly) {
  makeInstall(root_ / "install", "merged");
  fs::create_directories(root_ / "install" / "bin");
  fs::create_directories(root_ / "install" / "lib" / "auv_components");
  // An older copy of the install beside it: its libraries register the same components.
  makeInstall(root_ / "install-old", "merged");
  fs::create_directories(root_ / "install-old" / "lib" / "auv_components");
  const auto dirs = componentSearchPath(root_ / "install" / "bin" / "auv");
  EXPECT_EQ(dirs, std::vector<fs::path>{root_ / "install" / "lib" / "auv_components"});
}

TEST_F(ComponentSearchPathTest, IsolatedInstallLooksInEveryPackagePrefix) {
  makeInstall(root_ / "install", "isolated");
  fs::create_directories(root_ / "install" / "auv_bringup" / "bin");
  fs::create_directories(root_ / "install" / "auv_recorder" / "lib" / "auv_components");
  const auto dirs = componentSearchPath(root_ / "install" / "auv_bringup" / "bin" / "auv");
  EXPECT_TRUE(contains(dirs, root_ / "install" / "auv_bringup" / "lib" / "auv_components"));
  EXPECT_TRUE(contains(dirs, root_ / "install" / "auv_recorder" / "lib" / "auv_components"));
}

TEST_F(ComponentSearchPathTest, NoLayoutFileMeansNoNeighbours) {
  fs::create_directories(root_ / "prefix" / "bin");
  fs::create_directories(root_ / "elsewhere" / "lib" / "auv_components");
  const auto dirs = componentSearchPath(root_ / "prefix" / "bin" / "auv");
  EXPECT_EQ(dirs, std::vector<fs::path>{root_ / "prefix" / "lib" / "auv_components"});
}

TEST_F(ComponentSearchPathTest, EnvironmentFoldersComeFirstAndPrefixPathsLast) {
  const ScopedEnv components("AUV_COMPONENT_PATH", "/opt/a::/opt/b");
  const ScopedEnv prefixes("CMAKE_PREFIX_PATH", "/opt/c");
  const auto dirs = componentSearchPath(root_ / "install" / "bin" / "auv");
  ASSERT_EQ(dirs.size(), 4u);
  EXPECT_EQ(dirs[0], fs::path("/opt/a"));
  EXPECT_EQ(dirs[1], fs::path("/opt/b"));  // the empty entry is skipped
  EXPECT_EQ(dirs[2], root_ / "install" / "lib" / "auv_components");
  EXPECT_EQ(dirs[3], fs::path("/opt/c/lib/auv_components"));
  // Without an executable (unreadable /proc/self/exe): the environment's folders only.
  EXPECT_EQ(componentSearchPath(fs::path()).size(), 3u);
}

}  // namespace
}  // namespace auv::interfaces
