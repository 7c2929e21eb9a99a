// `auv recon run`: stage order, up-to-date skipping, options and config checks (every stage's
// section reaches it, bad ones refused before anything runs), and a real chain features ->
// match -> sfm on Sceaux castle at quarter resolution.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "../support/quarter_sceaux.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/pipeline/pipeline.h"
#include "auv/recon/scene/colmap_text.h"

namespace auv::recon::pipeline {
namespace {

namespace fs = std::filesystem;

fs::path freshFolder(const std::string& name) {
  const fs::path folder =
      fs::temp_directory_path() / ("auv_pipeline_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(folder);
  fs::create_directories(folder);
  return folder;
}

void touch(const fs::path& file, fs::file_time_type when) {
  fs::create_directories(file.parent_path());
  std::ofstream(file) << "x";
  fs::last_write_time(file, when);
}

TEST(Pipeline, StagesComeInThePapersOrder) {
  EXPECT_EQ(stageNames(), (std::vector<std::string>{"keyframes", "correct", "features", "match",
                                                    "sfm", "dense", "mesh", "restore", "texture"}));
}

TEST(Pipeline, OutputIsUpToDateOnlyWhenNewerThanEveryInput) {
  const fs::path root = freshFolder("dates");
  const auto now = fs::file_time_type::clock::now();
  const auto hour = std::chrono::hours(1);
  touch(root / "in" / "a.png", now - 3 * hour);
  touch(root / "in" / "sub" / "b.png", now - 2 * hour);
  touch(root / "out" / "x.txt", now - hour);
  touch(root / "out" / "y.txt", now - hour / 2);
  EXPECT_TRUE(upToDate({root / "in"}, {root / "out"}));
  // An input file changed after the output: out of date.
  touch(root / "in" / "sub" / "b.png", now);
  EXPECT_FALSE(upToDate({root / "in"}, {root / "out"}));
  // One output file older than an input: out of date (a half-updated output never counts).
  touch(root / "in" / "sub" / "b.png", now - 2 * hour);
  touch(root / "out" / "x.txt", now - 4 * hour);
  EXPECT_FALSE(upToDate({root / "in"}, {root / "out"}));
  // Hidden entries (staging folders) do not count.
  touch(root / "out" / "x.txt", now - hour);
  touch(root / "in" / ".staging" / "c.png", now);
  EXPECT_TRUE(upToDate({root / "in"}, {root / "out"}));
  // No output or no input: run.
  EXPECT_FALSE(upToDate({root / "in"}, {root / "missing"}));
  EXPECT_FALSE(upToDate({root / "missing"}, {root / "out"}));
  // Several inputs, files and folders.
  touch(root / "extra.yaml", now);
  EXPECT_FALSE(upToDate({root / "in", root / "extra.yaml"}, {root / "out"}));
  fs::remove_all(root);
}

TEST(Pipeline, OptionsNameTheBadField) {
  PipelineOptions options;
  options.from = "dense";
  options.to = "sfm";
  try {
    options.check();
    FAIL();
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("from = dense"), std::string::npos) << e.what();
  }
  options = {};
  options.to = "render";
  EXPECT_THROW(options.check(), OptionError);
  options = {};
  options.config = "/nonexistent/recon.yaml";
  EXPECT_THROW(options.check(), OptionError);
}

TEST(Pipeline, AFailingStageStopsTheRunNamingIt) {
  const fs::path root = freshFolder("fail");
  PipelineOptions options;
  options.from = "features";
  options.to = "sfm";
  std::ostringstream log;
  try {
    runPipeline(Survey(root), options, log);
    FAIL() << "expected a StageError";
  } catch (const StageError& e) {
    EXPECT_EQ(e.stage(), "features");
    EXPECT_NE(std::string(e.what()).find("corrected"), std::string::npos) << e.what();
  }
  EXPECT_NE(log.str().find("run: features ..."), std::string::npos) << log.str();
  EXPECT_EQ(log.str().find("run: match"), std::string::npos) << log.str();
  fs::remove_all(root);
}

/// A recon.yaml in `root` with `text`; returns its path.
std::string writeConfig(const fs::path& root, const std::string& text) {
  const fs::path file = root / "recon.yaml";
  std::ofstream(file) << text;
  return file.string();
}

/// The message of the StageError `run` throws (empty, and a test failure, if none).
std::string stageFailure(const Survey& survey, const PipelineOptions& options) {
  std::ostringstream log;
  try {
    runPipeline(survey, options, log);
  } catch (const StageError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected a StageError; log: " << log.str();
  return "";
}

// Each stage's section reaches the stage: a value the stage's own error message shows, on
// surveys too small for the stage to run (so no heavy work).
TEST(Pipeline, ConfigSectionsReachKeyframesCorrectAndDense) {
  const fs::path root = freshFolder("sections");
  const Survey survey(root);
  fs::create_directories(survey.recordings() / "left");  // no videos
  fs::create_directories(survey.keyframes() / "left");   // no keyframes
  fs::create_directories(survey.corrected());
  fs::create_directories(survey.sparse());
  // A sparse model of 3 images and no point.
  std::ofstream(survey.sparse() / "cameras.txt") << "1 PINHOLE 64 48 50 50 31.5 23.5\n";
  std::ofstream(survey.sparse() / "points3D.txt") << "";
  {
    std::ofstream images(survey.sparse() / "images.txt");
    for (int i = 1; i <= 3; ++i)
      images << i << " 1 0 0 0 " << i << " 0 0 1 left/" << i << ".png\n\n";
  }
  PipelineOptions options;
  options.force = true;

  options.from = options.to = "keyframes";
  EXPECT_NE(stageFailure(survey, options).find("no videos"), std::string::npos);
  options.config = writeConfig(root, "keyframes:\n  camera: [forward]\n");
  std::string what = stageFailure(survey, options);
  EXPECT_NE(what.find("forward"), std::string::npos) << what;
  EXPECT_NE(what.find("no such camera folder"), std::string::npos) << what;

  options.config.clear();
  options.from = options.to = "correct";
  EXPECT_NE(stageFailure(survey, options).find("camera 'left'"), std::string::npos);
  options.config = writeConfig(root, "correct:\n  camera: [down]\n");
  what = stageFailure(survey, options);
  EXPECT_NE(what.find("camera 'down'"), std::string::npos) << what;

  // Defaults: 3 registered images are enough to start (then no neighbour: no point shared).
  options.config.clear();
  options.from = options.to = "dense";
  what = stageFailure(survey, options);
  EXPECT_EQ(what.find("at least"), std::string::npos) << what;
  options.config = writeConfig(root, "dense:\n  min_registered_images: 10\n");
  what = stageFailure(survey, options);
  EXPECT_NE(what.find("3 registered images (at least 10 needed"), std::string::npos) << what;
  fs::remove_all(root);
}

// The whole file is read before the first stage runs: a bad value or key in any section, or a
// section that names nothing `run` knows, is an error naming the file, section and key.
TEST(Pipeline, BadConfigSectionsAreRefusedBeforeAnyStageRuns) {
  const fs::path root = freshFolder("bad_config");
  const Survey survey(root);
  PipelineOptions options;
  options.from = options.to = "keyframes";  // dense is not even in the range
  auto refusal = [&](const std::string& text) {
    options.config = writeConfig(root, text);
    std::ostringstream log;
    try {
      runPipeline(survey, options, log);
    } catch (const StageError& e) {
      ADD_FAILURE() << "a stage ran: " << e.what();
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(log.str(), "") << "a stage started before the config was checked";
      EXPECT_NE(std::string(e.what()).find(options.config), std::string::npos) << e.what();
      return std::string(e.what());
    }
    ADD_FAILURE() << "accepted: " << text;
    return std::string();
  };
  std::string what = refusal("dense:\n  max_image_size: 10\n");  // out of range
  EXPECT_NE(what.find("dense: max_image_size = 10"), std::string::npos) << what;
  what = refusal("dense:\n  max_image_size: ten\n");  // not a number
  EXPECT_NE(what.find("dense.max_image_size"), std::string::npos) << what;
  what = refusal("dense:\n  max_image_sise: 512\n");  // unknown key
  EXPECT_NE(what.find("dense.max_image_sise"), std::string::npos) << what;
  what = refusal("keyframes:\n  lk_window: 4\n");  // the stage's own check (odd window)
  EXPECT_NE(what.find("keyframes: "), std::string::npos) << what;
  EXPECT_NE(what.find("lk_window"), std::string::npos) << what;
  what = refusal("sfm:\n  threads: 2\nsfn:\n  threads: 2\n");  // a typo of a stage
  EXPECT_NE(what.find("section 'sfn'"), std::string::npos) << what;
  EXPECT_NE(what.find("did you mean 'sfm'?"), std::string::npos) << what;
  what = refusal("- keyframes\n- dense\n");
  EXPECT_NE(what.find("map"), std::string::npos) << what;

  // Sections of the pipeline itself and of the commands reading the same file are accepted:
  // the run goes on to the keyframes stage (which fails: no recordings/).
  options.config = writeConfig(root,
                               "run:\n  force: true\nevaluate:\n  anything: 1\n"
                               "dense:\n  max_image_size: 512\nmesh: {}\ntexture:\n");
  EXPECT_NE(stageFailure(survey, options).find("recordings"), std::string::npos);
  fs::remove_all(root);
}

TEST(Pipeline, ChainsFeaturesMatchAndSfmThenSkipsWhatIsUpToDate) {
  const fs::path root = freshFolder("chain");
  const Survey survey(root);
  if (!test_support::quarterSceaux(survey)) GTEST_SKIP() << "Sceaux castle data absent";
  {
    std::ofstream config(root / "recon.yaml");
    config << "features:\n  threads: 2\nmatch:\n  threads: 2\nsfm:\n  threads: 2\n";
  }
  PipelineOptions options;
  options.from = "features";
  options.to = "sfm";
  options.config = (root / "recon.yaml").string();
  std::ostringstream log;
  PipelineResult first = runPipeline(survey, options, log);
  ASSERT_EQ(first.stages.size(), 3u);
  for (const auto& s : first.stages) EXPECT_EQ(s.outcome, StageOutcome::RAN) << s.stage;
  const scene::Reconstruction model = scene::readColmapText(survey.sparse());
  EXPECT_GE(model.images.size(), 8u);  // quarter resolution: not every view may register
  const auto sparse_time = fs::last_write_time(survey.sparse() / "images.txt");

  // Nothing changed: every stage is skipped and sparse/ is untouched.
  PipelineResult second = runPipeline(survey, options, log);
  for (const auto& s : second.stages) EXPECT_EQ(s.outcome, StageOutcome::UP_TO_DATE) << s.stage;
  EXPECT_EQ(fs::last_write_time(survey.sparse() / "images.txt"), sparse_time);

  // New verified matches: sfm runs again, features and match do not.
  fs::last_write_time(survey.root() / "features" / "matches" / "pairs.csv",
                      fs::file_time_type::clock::now() + std::chrono::seconds(1));
  PipelineResult third = runPipeline(survey, options, log);
  ASSERT_EQ(third.stages.size(), 3u);
  EXPECT_EQ(third.stages[0].outcome, StageOutcome::UP_TO_DATE);
  EXPECT_EQ(third.stages[1].outcome, StageOutcome::UP_TO_DATE);
  EXPECT_EQ(third.stages[2].outcome, StageOutcome::RAN);
  EXPECT_GT(fs::last_write_time(survey.sparse() / "images.txt"), sparse_time);

  // A bad sfm option in the config names the section and the key; sparse/ stays.
  {
    std::ofstream config(root / "bad.yaml");
    config << "sfm:\n  max_reprojection_error: -1\n";
  }
  PipelineOptions force = options;
  force.config = (root / "bad.yaml").string();
  force.from = "sfm";
  force.force = true;
  try {
    runPipeline(survey, force, log);
    FAIL() << "a negative max_reprojection_error was accepted";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("sfm"), std::string::npos) << what;
    EXPECT_NE(what.find("max_reprojection_error"), std::string::npos) << what;
  }
  EXPECT_EQ(scene::readColmapText(survey.sparse()).images.size(), model.images.size());
  fs::remove_all(root);
}

}  // namespace
}  // namespace auv::recon::pipeline
