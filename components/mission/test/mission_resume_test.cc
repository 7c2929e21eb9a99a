// A mission handler restarted within a launch goes on with the mission: its progress (query,
// counters, ids, recoveries used) survives as progress.yaml and resume() re-issues the query in
// progress from where the vehicle is, with ids the planner and controller have not seen.
#include <gtest/gtest.h>

#include "auv/mission/mission_progress.h"
#include "executive_fixture.h"

namespace auv::mission {
namespace {
using namespace executive_test;

class MissionResumeTest : public MissionExecutiveTest {
 protected:
  /// Query 1 of two done, query 2 under way: the progress a crash would leave.
  MissionProgress progressMidMission() {
    startReady({query({10, 0, 5}, "first"), query({20, 0, 5}, "second")});
    const msg::Waypoint w = waypoint({10, 0, 5}, /*is_final=*/true);
    follow(w);
    moveTo({10, 0, 5});
    follow(waypoint({14, 0, 5}));
    EXPECT_EQ(executive.status().current_query_index(), 1);
    MissionProgress progress = executive.progress();
    progress.launch_id = "launch-1";
    progress.plan.name = "inspection";
    return progress;
  }
};

TEST_F(MissionResumeTest, ProgressSurvivesItsFileFormat) {
  const MissionProgress before = progressMidMission();
  const MissionProgress after = parseProgress(toYaml(before), "progress.yaml");
  EXPECT_EQ(after.launch_id, "launch-1");
  EXPECT_EQ(after.mission_id, "m-1");
  EXPECT_EQ(after.state, msg::MISSION_STATE_EXECUTING);
  EXPECT_EQ(after.query_index, 1);
  EXPECT_EQ(after.queries_succeeded, 1u);
  EXPECT_EQ(after.waypoints_received, before.waypoints_received);
  EXPECT_EQ(after.next_query_id, before.next_query_id);
  EXPECT_EQ(after.next_command_id, before.next_command_id);
  EXPECT_EQ(after.plan.name, "inspection");
  ASSERT_EQ(after.plan.queries.size(), 2u);
  EXPECT_EQ(after.plan.queries[1].name, "second");
  EXPECT_EQ(after.plan.queries[1].goal, Eigen::Vector3d(20, 0, 5));
  EXPECT_TRUE(after.running());
}

TEST_F(MissionResumeTest, RestartedHandlerReissuesTheQueryInProgressWithNewIds) {
  const MissionProgress progress = progressMidMission();
  const uint64_t last_query_id = executive.status().current_query_id();

  MissionExecutive restarted(defaults());
  executive = std::move(restarted);  // the fixture's helpers drive the new one
  vehicle = {12, 1, 5};
  odometry();
  controller();
  executive.setPlannerPresent(true);
  std::string why;
  ASSERT_TRUE(executive.resume(progress, t, &why)) << why;
  const MissionExecutive::Outbox out = executive.takeOutbox();
  EXPECT_EQ(state(), msg::MISSION_STATE_WAITING_FOR_WAYPOINT) << message();
  EXPECT_EQ(executive.status().mission_id(), "m-1");
  EXPECT_EQ(executive.status().current_query_index(), 1);
  EXPECT_EQ(executive.status().queries_succeeded(), 1u);
  ASSERT_EQ(out.queries.size(), 1u);
  EXPECT_GT(out.queries[0].query_id(), last_query_id);
  EXPECT_EQ(vector(out.queries[0].start().position()), Eigen::Vector3d(12, 1, 5));
  EXPECT_EQ(vector(out.queries[0].goal().position()), Eigen::Vector3d(20, 0, 5));
  ASSERT_FALSE(out.events.empty());
  EXPECT_EQ(out.events[0].name, "RESUMED");
  EXPECT_CONTAINS(out.events[0].detail, "query 2/2");

  // It runs to success as any mission.
  msg::Waypoint last = waypoint({20, 0, 5}, /*is_final=*/true);
  last.query_id(out.queries[0].query_id());
  follow(last);
  moveTo({20, 0, 5});
  EXPECT_EQ(state(), msg::MISSION_STATE_SUCCEEDED);
  EXPECT_EQ(executive.status().queries_succeeded(), 2u);
}

TEST_F(MissionResumeTest, RecoveriesUsedBeforeTheRestartStillCount) {
  MissionProgress progress = progressMidMission();
  progress.query_recoveries = 3;  // all of max_recoveries 3
  progress.recoveries = 3;
  MissionExecutive restarted(defaults());
  executive = std::move(restarted);
  odometry();
  controller();
  executive.setPlannerPresent(true);
  std::string why;
  ASSERT_TRUE(executive.resume(progress, t, &why)) << why;
  executive.takeOutbox();
  controller(/*safety=*/true);
  EXPECT_EQ(state(), msg::MISSION_STATE_ABORTED);
  EXPECT_CONTAINS(message(), "recoveries exhausted (3 of max_recoveries 3");
}

TEST_F(MissionResumeTest, OnlyARunningMissionIsResumed) {
  MissionProgress progress = progressMidMission();
  std::string why;
  EXPECT_FALSE(executive.resume(progress, t, &why)) << "one is running";
  EXPECT_CONTAINS(why, "is EXECUTING");
  MissionExecutive fresh(defaults());
  progress.state = msg::MISSION_STATE_SUCCEEDED;
  EXPECT_FALSE(fresh.resume(progress, t, &why));
  EXPECT_CONTAINS(why, "had ended (SUCCEEDED)");
  progress.state = msg::MISSION_STATE_EXECUTING;
  progress.query_index = 2;
  EXPECT_FALSE(fresh.resume(progress, t, &why));
  EXPECT_CONTAINS(why, "query index 2");
}

TEST(MissionProgressFile, DamagedFilesAreRefusedNamingTheField) {
  const auto refused = [](const std::string& text) {
    try {
      parseProgress(text, "run/mission/progress.yaml");
    } catch (const MissionError& error) {
      return std::string(error.what());
    }
    return std::string("accepted");
  };
  EXPECT_CONTAINS(refused("[1, 2"), "run/mission/progress.yaml: not YAML");
  EXPECT_CONTAINS(refused("- a list"), "not a map");
  EXPECT_CONTAINS(refused("launch_id: x\nmission_id: m\n"), "field 'state' missing");
  EXPECT_CONTAINS(refused("launch_id: x\nmission_id: m\nstate: FLYING\n"), "unknown FLYING");
  const MissionProgress good = [] {
    MissionProgress p;
    p.mission_id = "m";
    p.state = msg::MISSION_STATE_EXECUTING;
    p.query_index = 0;
    p.plan.name = "n";
    p.plan.queries.push_back(query({10, 0, 5}));
    p.plan.queries[0].bounds_min = {-50, -50, 0};
    p.plan.queries[0].bounds_max = {50, 50, 20};
    return p;
  }();
  EXPECT_EQ(refused(toYaml(good)), "accepted");
  std::string bad_index = toYaml(good);
  bad_index.replace(bad_index.find("query_index: 0"), 14, "query_index: 4");
  EXPECT_CONTAINS(refused(bad_index), "field 'query_index': 4 is not one of the plan's 1");
  std::string bad_number = toYaml(good);
  bad_number.replace(bad_number.find("next_query_id: 1"), 16, "next_query_id: x");
  EXPECT_CONTAINS(refused(bad_number), "field 'next_query_id': not a number");
}

}  // namespace
}  // namespace auv::mission
