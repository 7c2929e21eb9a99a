// `auv recon run --executor slurm`, `status` and `cancel` as a user runs them, against a real
// Slurm: scripts/slurm-cluster.sh brings up slurmctld and two slurmd hosts (network namespaces)
// for the tests that need one, which skip without root or without Slurm installed.
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <thread>

#include <gtest/gtest.h>

#include "../support/quarter_sceaux.h"
#include "auv/recon/cluster/slurm.h"
#include "auv/recon/common/report.h"
#include "auv/recon/scene/colmap_text.h"

namespace auv::recon::cluster {
namespace {

namespace fs = std::filesystem;

fs::path freshFolder(const std::string& name) {
  const fs::path folder =
      fs::temp_directory_path() / ("auv_cluster_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(folder);
  fs::create_directories(folder);
  return folder;
}

/// `auv-recon <args>`.
CommandOutput tool(std::vector<std::string> args) {
  args.insert(args.begin(), AUV_RECON_TOOL);
  return runCommand(args, 1800);
}

/// Sets an environment variable for one scope.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv() {
    if (old_.empty()) {
      unsetenv(name_);
    } else {
      setenv(name_, old_.c_str(), 1);
    }
  }

 private:
  const char* name_;
  std::string old_;
};

TEST(SlurmRunTest, WithoutSlurmNothingIsSubmittedAndTheReasonIsNamed) {
  const fs::path root = freshFolder("no_slurm");
  const fs::path empty = root / "bin";
  fs::create_directories(empty);
  ScopedEnv path("PATH", empty.string());  // no sbatch anywhere
  const CommandOutput run = tool({"run", root.string(), "--executor", "slurm"});
  EXPECT_EQ(run.exit_code, 2) << run.err;
  EXPECT_NE(run.err.find("no Slurm on this machine"), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(root / "slurm"));
  const CommandOutput status = tool({"status", root.string()});
  EXPECT_EQ(status.exit_code, 2);
  EXPECT_NE(status.err.find("no Slurm jobs were submitted"), std::string::npos) << status.err;
  // Slurm's options without the Slurm executor are a mistake, said so.
  const CommandOutput local = tool({"run", root.string(), "--partition", "survey"});
  EXPECT_EQ(local.exit_code, 2);
  EXPECT_NE(local.err.find("are for --executor slurm"), std::string::npos) << local.err;
  fs::remove_all(root);
}

/// A private two-host cluster for one test (scripts/slurm-cluster.sh).
class SlurmCluster : public ::testing::Test {
 protected:
  void SetUp() override {
    if (::geteuid() != 0) GTEST_SKIP() << "needs root: the cluster's hosts are network namespaces";
    if (runCommand({"slurmctld", "-V"}).exit_code != 0) {
      GTEST_SKIP() << "Slurm is not installed (scripts/install-deps.sh)";
    }
    dir_ = freshFolder("cluster");
    std::vector<std::string> up_args = {
        AUV_SLURM_CLUSTER_SCRIPT, "up", "--dir",          dir_.string(), "--nodes", "2",
        "--cpus-per-node",        "1",  "--mem-per-node", "4000"};
    if (!hidden().empty()) {
      up_args.push_back("--hide");
      up_args.push_back(hidden().string());
    }
    const CommandOutput up = runCommand(up_args, 180);
    ASSERT_EQ(up.exit_code, 0) << up.out << up.err;
    conf_ = std::make_unique<ScopedEnv>("SLURM_CONF", (dir_ / "slurm.conf").string());
  }
  void TearDown() override {
    conf_.reset();
    if (!dir_.empty()) {
      runCommand({AUV_SLURM_CLUSTER_SCRIPT, "down", "--dir", dir_.string()}, 120);
      fs::remove_all(dir_);
    }
    if (!hidden().empty()) fs::remove_all(hidden());
  }
  /// A folder the hosts do not see (slurm-cluster.sh --hide); empty: none.
  virtual fs::path hidden() const { return {}; }

  /// `auv recon status` until no job is pending or running (or `timeout_s`); its last output.
  CommandOutput waitForJobs(const fs::path& survey, double timeout_s) {
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    CommandOutput status;
    while (std::chrono::steady_clock::now() < deadline) {
      status = tool({"status", survey.string()});
      if (status.out.find("PENDING") == std::string::npos &&
          status.out.find("RUNNING") == std::string::npos &&
          status.out.find("COMPLETING") == std::string::npos) {
        break;
      }
      std::this_thread::sleep_for(std::chrono::seconds(2));
    }
    return status;
  }

  fs::path dir_;
  std::unique_ptr<ScopedEnv> conf_;
};

TEST_F(SlurmCluster, AChainOfStagesRunsAsJobsAndIsFollowed) {
  const fs::path root = freshFolder("chain");
  const Survey survey(root);
  if (!test_support::quarterSceaux(survey)) GTEST_SKIP() << "Sceaux castle data absent";
  {
    std::ofstream config(root / "recon.yaml");
    // The features' threads are left to the job: the CPUs Slurm gave it (1 per host here).
    config << "match:\n  threads: 1\nsfm:\n  threads: 1\n";
  }
  // Bad input first: a partition the cluster does not have; nothing is submitted.
  const CommandOutput bad = tool({"run", root.string(), "--executor", "slurm", "--from", "features",
                                  "--to", "sfm", "--partition", "nosuch"});
  EXPECT_EQ(bad.exit_code, 2) << bad.err;
  EXPECT_NE(bad.err.find("--partition nosuch: no such partition (the cluster has: survey)"),
            std::string::npos)
      << bad.err;
  EXPECT_FALSE(fs::exists(root / "slurm" / "jobs.json"));

  // features and match as two array tasks each (one per host) and a merge, then sfm.
  const CommandOutput run =
      tool({"run", root.string(), "--executor", "slurm", "--from", "features", "--to", "sfm",
            "--config", (root / "recon.yaml").string(), "--mem-mb", "2000", "--shards", "2"});
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  EXPECT_NE(run.out.find("5 jobs submitted to Slurm"), std::string::npos) << run.out;
  EXPECT_NE(run.err.find("run: features.shards: submitted as job"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("(2 array tasks)"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("run: match.merge: submitted as job"), std::string::npos) << run.err;
  // A second submission while the first is queued is refused, naming the running job.
  const CommandOutput twice = tool({"run", root.string(), "--executor", "slurm"});
  EXPECT_EQ(twice.exit_code, 2);
  EXPECT_NE(twice.err.find("of an earlier submission is"), std::string::npos) << twice.err;

  const CommandOutput status = waitForJobs(root, 1500);
  EXPECT_EQ(status.exit_code, 0) << status.out << status.err;
  EXPECT_NE(status.out.find("status: 5 of 5 jobs completed"), std::string::npos) << status.out;
  // The two shards ran at once, one on each host.
  const std::string shards_line = status.out.substr(status.out.find("features.shards"));
  const std::string shards_row = shards_line.substr(0, shards_line.find('\n'));
  EXPECT_NE(shards_row.find("n1"), std::string::npos) << status.out;
  EXPECT_NE(shards_row.find("n2"), std::string::npos) << status.out;
  EXPECT_GE(scene::readColmapText(survey.sparse()).images.size(), 8u);
  // The job's script set OMP_NUM_THREADS to its one CPU (this machine has more cores).
  EXPECT_EQ(readReportSection(survey.report(), "features").value("threads", 0), 1);
  // Each stage ran on a host of the cluster, in its own job, and logged there.
  for (const char* stage :
       {"features.shards", "features.merge", "match.shards", "match.merge", "sfm"}) {
    bool logged = false;
    for (const auto& entry : fs::directory_iterator(root / "slurm")) {
      logged = logged || entry.path().filename().string().rfind(std::string(stage) + "-", 0) == 0;
    }
    EXPECT_TRUE(logged) << stage;
  }

  // Cancel: a new submission (forced, so the jobs have work) is stopped while queued.
  const CommandOutput again = tool({"run", root.string(), "--executor", "slurm", "--from",
                                    "features", "--to", "sfm", "--force"});
  ASSERT_EQ(again.exit_code, 0) << again.err;
  const CommandOutput cancel = tool({"cancel", root.string()});
  EXPECT_EQ(cancel.exit_code, 0) << cancel.err;
  EXPECT_NE(cancel.out.find("cancel: 3 job(s) cancelled"), std::string::npos) << cancel.out;
  const CommandOutput after = waitForJobs(root, 120);
  EXPECT_NE(after.out.find("CANCELLED"), std::string::npos) << after.out;
  fs::remove_all(root);
}

/// A cluster whose hosts do not see one folder of this machine (as a node's local disk).
class ClusterNotSeeingASurvey : public SlurmCluster {
 protected:
  fs::path hidden() const override {
    return fs::temp_directory_path() / ("auv_cluster_test_hidden_" + std::to_string(::getpid()));
  }
};

TEST_F(ClusterNotSeeingASurvey, IsRefusedBeforeAnyStageIsSubmitted) {
  const fs::path root = hidden() / "survey";
  fs::create_directories(root);
  const CommandOutput run = tool({"run", root.string(), "--executor", "slurm"});
  EXPECT_EQ(run.exit_code, 2) << run.err;
  EXPECT_NE(run.err.find("the compute nodes of partition survey cannot see " + root.string()),
            std::string::npos)
      << run.err;
  EXPECT_FALSE(fs::exists(root / "slurm"));  // not even the probe's folder
  const CommandOutput queue = runCommand({"squeue", "--noheader"});
  EXPECT_EQ(queue.out, "");  // nothing left queued
}

}  // namespace
}  // namespace auv::recon::cluster
