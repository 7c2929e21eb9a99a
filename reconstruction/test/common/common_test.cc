// Survey folders, staged outputs, report.json, option binding: the pieces every stage uses.
#include <gtest/gtest.h>
#include <sched.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <fstream>
#include <random>

#include <opencv2/core/utility.hpp>

#include "auv/recon/common/option_set.h"
#include "auv/recon/common/progress.h"
#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/staged_output.h"
#include "auv/recon/common/survey.h"
#include "auv/recon/common/threads.h"

namespace fs = std::filesystem;
using namespace auv::recon;

namespace {
struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() / ("auv_recon_common_" + std::to_string(::getpid()) + "_" +
                                        std::to_string(std::random_device{}()));
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
};

std::string readText(const fs::path& file) {
  std::ifstream in(file);
  return std::string(std::istreambuf_iterator<char>(in), {});
}
}  // namespace

TEST(StagedOutput, CommitReplacesThePreviousOutput) {
  TempDir dir;
  const fs::path sparse = dir.path / "sparse";
  fs::create_directories(sparse);
  std::ofstream(sparse / "old.txt") << "old";
  {
    StagedOutput staged(sparse);
    EXPECT_NE(staged.path(), sparse);
    std::ofstream(staged.path() / "new.txt") << "new";
    EXPECT_TRUE(fs::exists(sparse / "old.txt"));  // untouched until commit
    staged.commit();
  }
  EXPECT_FALSE(fs::exists(sparse / "old.txt"));
  EXPECT_EQ(readText(sparse / "new.txt"), "new");
  size_t entries = 0;
  for (const auto& entry : fs::directory_iterator(dir.path)) {
    (void)entry;
    ++entries;
  }
  EXPECT_EQ(entries, 1u) << "staging and old folders are removed";
}

TEST(StagedOutput, AStageThatFailsLeavesTheEarlierOutputIntact) {
  TempDir dir;
  const fs::path dense = dir.path / "dense";
  fs::create_directories(dense);
  std::ofstream(dense / "fused.ply") << "earlier";
  try {
    StagedOutput staged(dense / "");  // a trailing slash names the same folder
    std::ofstream(staged.path() / "fused.ply") << "half";
    throw StageError("dense", "the cloud is empty");
  } catch (const StageError& e) {
    EXPECT_EQ(std::string(e.what()), "dense: the cloud is empty");
    EXPECT_EQ(e.stage(), "dense");
  }
  EXPECT_EQ(readText(dense / "fused.ply"), "earlier");
  for (const auto& entry : fs::directory_iterator(dir.path)) {
    EXPECT_EQ(entry.path().filename(), "dense") << "staging folder left behind";
  }
}

TEST(Report, EachStageReplacesOnlyItsOwnSection) {
  TempDir dir;
  const fs::path report = dir.path / "report.json";
  updateReport(report, "keyframes", {{"keyframes", 12}});
  updateReport(report, "sfm", {{"images_registered", 10}});
  updateReport(report, "keyframes", {{"keyframes", 14}});
  const auto json = readReport(report);
  EXPECT_EQ(json["format"], "auv-recon-report 1");
  EXPECT_EQ(json["stages"]["keyframes"]["keyframes"], 14);
  EXPECT_EQ(json["stages"]["sfm"]["images_registered"], 10);
}

TEST(Report, AnUnreadableReportIsKeptAsideNotLost) {
  TempDir dir;
  const fs::path report = dir.path / "report.json";
  std::ofstream(report) << "{ not json";
  EXPECT_THROW(readReport(report), std::runtime_error);
  updateReport(report, "mesh", {{"triangles", 5}});
  EXPECT_EQ(readReport(report)["stages"]["mesh"]["triangles"], 5);
  EXPECT_EQ(readText(dir.path / "report.json.unreadable"), "{ not json");
}

TEST(Survey, CameraFoldersAreSortedAndAMissingFolderIsNamed) {
  TempDir dir;
  Survey survey(dir.path);
  try {
    Survey::cameraFolders(survey.keyframes(), "keyframes");
    FAIL();
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find(survey.keyframes().string()), std::string::npos);
  }
  fs::create_directories(survey.keyframes() / "right");
  fs::create_directories(survey.keyframes() / "left");
  fs::create_directories(survey.keyframes() / ".left.staging-1");
  EXPECT_EQ(Survey::cameraFolders(survey.keyframes(), "keyframes"),
            (std::vector<std::string>{"left", "right"}));
}

struct ToyOptions {
  double min_motion_px = 30;
  int pyramid_levels = 3;
  size_t max_features = 500;
  bool adaptive = false;
  std::string method = "grey";
  std::vector<std::string> cameras;
};

OptionSet bind(ToyOptions& o) {
  OptionSet set("keyframes");
  set.add("min_motion_px", &o.min_motion_px, "px");
  set.add("pyramid_levels", &o.pyramid_levels, "levels");
  set.add("max_features", &o.max_features, "count");
  set.add("adaptive", &o.adaptive, "flag");
  set.add("method", &o.method, "name");
  set.add("camera", &o.cameras, "camera ids");
  return set;
}

TEST(OptionSet, FlagsOverrideTheConfigFileWhereverItStands) {
  TempDir dir;
  const fs::path config = dir.path / "recon.yaml";
  std::ofstream(config) << "keyframes:\n  min_motion_px: 12.5\n  max_features: 800\n"
                           "  camera: [left, right]\nsfm:\n  anything: 1\n";
  ToyOptions o;
  std::string survey;
  OptionSet set = bind(o);
  set.positional("survey", &survey, "folder");
  ASSERT_TRUE(set.parse({"--min-motion-px", "20", "s1", "--config", config.string(), "--adaptive",
                         "--pyramid_levels=5"}));
  EXPECT_EQ(o.min_motion_px, 20);  // the flag wins over the file
  EXPECT_EQ(o.max_features, 800u);
  EXPECT_EQ(o.pyramid_levels, 5);
  EXPECT_TRUE(o.adaptive);
  EXPECT_EQ(o.cameras, (std::vector<std::string>{"left", "right"}));
  EXPECT_EQ(survey, "s1");
}

TEST(OptionSet, BadValuesNameTheFlagOrTheFileAndKey) {
  TempDir dir;
  ToyOptions o;
  auto message = [&](const std::vector<std::string>& args) {
    OptionSet set = bind(o);
    try {
      set.parse(args);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message({"--min-motion-px", "fast"}), "--min-motion-px: expected a number, got 'fast'");
  EXPECT_EQ(message({"--max-features", "-3"}),
            "--max-features: expected a non-negative integer, got '-3'");
  EXPECT_EQ(message({"--colour", "x"}), "--colour: unknown option (`--help` lists them)");
  EXPECT_EQ(message({"--method"}), "--method: missing value");
  const fs::path config = dir.path / "bad.yaml";
  std::ofstream(config) << "keyframes:\n  min_motion: 3\n";
  const std::string unknown = message({"--config", config.string()});
  EXPECT_NE(unknown.find(config.string() + ": keyframes.min_motion: unknown setting"),
            std::string::npos)
      << unknown;
  EXPECT_NE(unknown.find("did you mean 'min_motion_px'?"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("known: min_motion_px, pyramid_levels"), std::string::npos) << unknown;
  std::ofstream(config) << "keyframes:\n  pyramid_levels: 2.5\n";
  EXPECT_EQ(message({"--config", config.string()}),
            config.string() + ": keyframes.pyramid_levels: expected an integer, got '2.5'");
  EXPECT_EQ(message({"--config", (dir.path / "missing.yaml").string()}),
            "--config: " + (dir.path / "missing.yaml").string() + ": cannot open the file");
  std::ofstream(config) << "keyframes:\n  min_motion_px: [1\n";
  EXPECT_EQ(message({"--config", config.string()}).rfind("--config: " + config.string() + ":", 0),
            0u);
}

// Flags and the file follow the one scalar rule of every reader (YAML 1.2 core schema).
TEST(OptionSet, ValuesFollowYaml12) {
  TempDir dir;
  ToyOptions o;
  auto message = [&](const std::vector<std::string>& args) {
    OptionSet set = bind(o);
    try {
      set.parse(args);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const fs::path config = dir.path / "recon.yaml";
  std::ofstream(config) << "keyframes:\n  adaptive: yes\n";
  EXPECT_EQ(
      message({"--config", config.string()}),
      config.string() + ": keyframes.adaptive: expected a boolean (true or false), got 'yes'");
  std::ofstream(config) << "keyframes:\n  min_motion_px: \"12\"\n";
  EXPECT_EQ(message({"--config", config.string()}),
            config.string() +
                ": keyframes.min_motion_px: expected a number, got \"12\" (a quoted string)");
  EXPECT_EQ(message({"--adaptive=on"}), "--adaptive: expected a boolean (true or false), got 'on'");
  EXPECT_EQ(message({"--min-motion-px", "0x1p3"}),
            "--min-motion-px: expected a number, got '0x1p3'");
  std::ofstream(config) << "keyframes:\n  max-features: 0x20\n  method: 5\n  adaptive: True\n";
  ASSERT_EQ(message({"--config", config.string(), "--pyramid-levels", "+4"}), "no error");
  EXPECT_EQ(o.max_features, 32u);  // either spelling of a key; a YAML 1.2 hex integer
  EXPECT_EQ(o.method, "5");        // strings take any scalar
  EXPECT_TRUE(o.adaptive);
  EXPECT_EQ(o.pyramid_levels, 4);
  std::ofstream(config) << "";
  EXPECT_EQ(message({"--config", config.string()}), "no error");  // an empty file sets nothing
}

TEST(OptionCheck, NamesTheFieldAndItsValue) {
  const double min_motion_px = -2;
  try {
    AUV_RECON_CHECK_OPTION(min_motion_px > 0, min_motion_px, "must be > 0");
    FAIL();
  } catch (const OptionError& e) {
    EXPECT_EQ(std::string(e.what()), "min_motion_px = -2: must be > 0");
  }
}

TEST(Progress, DurationsReadLikeAClock) {
  EXPECT_EQ(Progress::duration(5.2), "5 s");
  EXPECT_EQ(Progress::duration(62), "1:02");
  EXPECT_EQ(Progress::duration(3723), "1:02:03");
}

TEST(Progress, PlainModeCountsAndSummarises) {
  std::FILE* out = std::tmpfile();
  {
    Progress progress("keyframes left", "frames", 10, Progress::Mode::PLAIN, out);
    for (int i = 0; i < 10; ++i) progress.advance();
    EXPECT_EQ(progress.done(), 10u);
  }
  std::rewind(out);
  char line[256] = {};
  ASSERT_NE(std::fgets(line, sizeof line, out), nullptr);
  EXPECT_EQ(std::string(line).rfind("keyframes left: 10 frames in ", 0), 0u) << line;
  std::fclose(out);
}

// A Slurm job's script sets OMP_NUM_THREADS to the CPUs it was given; without it, the CPUs the
// process may run on (a cgroup's cpuset), not every core of the host.
TEST(DefaultThreadCount, FollowsOmpNumThreadsThenTheAffinityMask) {
  const char* saved = std::getenv("OMP_NUM_THREADS");
  const std::string earlier = saved ? saved : "";
  cpu_set_t mask;
  ASSERT_EQ(sched_getaffinity(0, sizeof(mask), &mask), 0);
  const int allowed = CPU_COUNT(&mask);
  unsetenv("OMP_NUM_THREADS");
  EXPECT_EQ(defaultThreadCount(), allowed);
  setenv("OMP_NUM_THREADS", "3", 1);
  EXPECT_EQ(defaultThreadCount(), 3);
  setenv("OMP_NUM_THREADS", "5,2", 1);  // one count per nesting level: the first
  EXPECT_EQ(defaultThreadCount(), 5);
  for (const char* bad : {"", "0", "-2", "four", "3x"}) {
    setenv("OMP_NUM_THREADS", bad, 1);
    EXPECT_EQ(defaultThreadCount(), allowed) << "OMP_NUM_THREADS=" << bad;
  }
  // A narrower mask (as Slurm's task/affinity or taskset sets) is followed.
  unsetenv("OMP_NUM_THREADS");
  if (allowed > 1) {
    cpu_set_t one;
    CPU_ZERO(&one);
    for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu) {
      if (CPU_ISSET(cpu, &mask)) {
        CPU_SET(cpu, &one);
        break;
      }
    }
    ASSERT_EQ(sched_setaffinity(0, sizeof(one), &one), 0);
    EXPECT_EQ(defaultThreadCount(), 1);
    ASSERT_EQ(sched_setaffinity(0, sizeof(mask), &mask), 0);
  }
  // OpenCV's own pool (TBB) follows the same count once limited.
  setenv("OMP_NUM_THREADS", "1", 1);
  limitLibraryThreads();
  EXPECT_EQ(cv::getNumThreads(), 1);
  unsetenv("OMP_NUM_THREADS");
  limitLibraryThreads();
  EXPECT_EQ(cv::getNumThreads(), allowed);
  if (saved) setenv("OMP_NUM_THREADS", earlier.c_str(), 1);
}
