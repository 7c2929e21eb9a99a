// `auv recon dense` as a user runs it: exit codes and messages.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "auv/recon/scene/colmap_text.h"
#include "synthetic_scene.h"

namespace fs = std::filesystem;

namespace auv::recon::dense {
namespace {

struct ToolRun {
  int exit_code = -1;
  std::string output;
};

ToolRun runTool(const std::string& arguments) {
  ToolRun run;
  const std::string command = std::string(AUV_RECON_TOOL) + " dense " + arguments + " 2>&1";
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return run;
  std::array<char, 512> buffer{};
  while (std::fgets(buffer.data(), buffer.size(), pipe) != nullptr) run.output += buffer.data();
  const int status = ::pclose(pipe);
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return run;
}

class DenseCommand : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(AUV_RECON_TOOL)) GTEST_SKIP() << "auv-recon not built: " << AUV_RECON_TOOL;
    root_ = fs::temp_directory_path() / ("dense_command_" + std::to_string(::getpid()));
    fs::create_directories(root_);
  }
  void TearDown() override { fs::remove_all(root_); }
  fs::path root_;
};

TEST_F(DenseCommand, MissingSparseModelIsAStageFailureNamingTheProducer) {
  const ToolRun run = runTool((root_ / "empty").string());
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("dense"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("auv recon sfm"), std::string::npos) << run.output;
}

TEST_F(DenseCommand, BadOptionValueIsAUsageErrorNamingTheField) {
  const ToolRun run = runTool((root_ / "empty").string() + " --max-neighbours 0");
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.output.find("max_neighbours = 0"), std::string::npos) << run.output;
  const ToolRun unknown = runTool((root_ / "empty").string() + " --no-such-flag 3");
  EXPECT_EQ(unknown.exit_code, 2) << unknown.output;
}

TEST_F(DenseCommand, WritesTheCloudOfASmallSurvey) {
  std::vector<View> views = testing::gridViews(2, 2, 0.35, 4.0, 160, 120, 150);
  std::vector<cv::Mat> depths;
  for (View& view : views) depths.push_back(testing::render(testing::Scene(), view));
  const fs::path survey = root_ / "survey";
  scene::writeColmapText(testing::sparseModel(views, depths, 8), survey / "sparse");
  testing::writeImages(views, survey / "corrected");
  const ToolRun run = runTool(survey.string() + " --min-points 100 --min-consistent 1");
  EXPECT_EQ(run.exit_code, 0) << run.output;
  EXPECT_TRUE(fs::exists(survey / "dense" / "fused.ply"));
  EXPECT_TRUE(fs::exists(survey / "dense" / "fused_views.bin"));
  EXPECT_NE(run.output.find("4 depth maps"), std::string::npos) << run.output;
}

}  // namespace
}  // namespace auv::recon::dense
