// MissionLog: the planner trees of the mission report (no DDS).
#include "auv/mission/mission_log.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace auv::mission {
namespace {

namespace fs = std::filesystem;

msg::PlannerTree treeOf(uint64_t query_id, int nodes) {
  msg::PlannerTree tree;
  tree.query_id(query_id);
  for (int i = 0; i < nodes; ++i) {
    msg::Point p;
    p.x(i);
    tree.nodes().push_back(p);
    tree.parents().push_back(i - 1);
    tree.costs().push_back(0.5 * i);
  }
  return tree;
}

// Rows of a CSV file after its header (-1: no such file).
int rows(const fs::path& path) {
  std::ifstream in(path);
  if (!in) return -1;
  int count = -1;
  for (std::string line; std::getline(in, line);) ++count;
  return count;
}

class MissionLogTest : public testing::Test {
 protected:
  void SetUp() override {
    char pattern[] = "/tmp/auv-mission-log-test-XXXXXX";
    ASSERT_NE(::mkdtemp(pattern), nullptr);
    dir_ = pattern;
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(MissionLogTest, ATreeIsWrittenOnceThePlannerMovedToAnotherQuery) {
  MissionLog log(dir_.string(), MissionPlan{"test", {}});
  log.tree(treeOf(1, 3));
  log.tree(treeOf(1, 5));  // the newest of query 1 is what counts
  EXPECT_EQ(rows(dir_ / "tree_1.csv"), -1) << "query 1 may still grow its tree";
  log.tree(treeOf(2, 4));
  // Query 1 is over: its last tree is on disk before the mission ends (and a crash keeps it).
  EXPECT_EQ(rows(dir_ / "tree_1.csv"), 5);
  EXPECT_EQ(rows(dir_ / "tree_2.csv"), -1);
  // A late tree of query 1 replaces its file when query 2's is written.
  log.tree(treeOf(1, 6));
  EXPECT_EQ(rows(dir_ / "tree_2.csv"), 4);
  log.finish(msg::MissionStatus(), nullptr);
  EXPECT_EQ(rows(dir_ / "tree_1.csv"), 6);
  EXPECT_EQ(rows(dir_ / "tree_2.csv"), 4);
}

}  // namespace
}  // namespace auv::mission
