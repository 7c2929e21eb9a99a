// The mission component on real DDS. The test's own node, on the other vendor, plays the
// planner, the controller and navigation: stale navigation aborts a running mission to a depth
// hold; a goal inside a known obstacle is refused by mission/start; mission/abort stops a
// running mission and refuses when none runs; the final mission/status is latched for late
// joiners; the mission log is complete when the mission ends; navigation arriving while the
// executor is busy is not stale. Each test on its own domain id (151..159, test/README.md).
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "auv/interfaces/executor.h"
#include "auv/interfaces/msg_eigen.h"
#include "auv/mission/components/mission_component.h"
#include "auv/mission/mission_progress.h"

namespace auv::mission {
namespace {

using namespace std::chrono_literals;
using interfaces::Node;
using interfaces::nodeOptions;
using interfaces::Vendor;

#define EXPECT_CONTAINS(text, part) \
  EXPECT_NE(std::string(text).find(part), std::string::npos) << "'" << (text) << "'"

msg::Point point(const Eigen::Vector3d& v) { return interfaces::toPoint(v); }
Eigen::Vector3d vector(const msg::Point& p) { return interfaces::toEigen(p); }

std::vector<std::string> missionParameters(std::vector<std::string> extra = {}) {
  std::vector<std::string> parameters = {
      "odometry_timeout:=0.5", "controller_timeout:=2.0", "readiness_timeout:=30.0",
      "no_solution_timeout:=30.0", "request_period:=0.5", "request_distance:=1.5",
      "tick_rate:=20.0", "map_resolution:=0.5", "goal_clearance:=1.0",
      // One periodic status per 100 s: what a late joiner gets is the latched one.
      "status_rate:=0.01"};
  parameters.insert(parameters.end(), extra.begin(), extra.end());
  return parameters;
}

/// A query from the vehicle to `goal` at 5 m, as the operator sends it to mission/start.
msg::PlannerQuery queryTo(const Eigen::Vector3d& goal) {
  MissionQuery query;
  query.goal = goal;
  query.goal_tolerance = 1.0;
  query.bounds_min = {-30, -30, 0};
  query.bounds_max = {30, 30, 20};
  return toPlannerQuery(query);
}

/// The mission component in its own node, and the test's node playing the planner, the
/// controller and navigation, spun by one executor.
class MissionHarness {
 public:
  /// `before_activate` may add waitables to the mission's node that run before its tick.
  MissionHarness(Vendor mission_vendor, Vendor player_vendor, int domain,
                 std::vector<std::string> extra_parameters = {},
                 const std::function<void(Node&)>& before_activate = {})
      : mission_node_("mission", nodeOptions(mission_vendor, domain,
                                             missionParameters(std::move(extra_parameters)))),
        player_("player", nodeOptions(player_vendor, domain)) {
    mission.configure(mission_node_);
    odometry_pub_ = player_.createPublisher<msg::Odometry>("nav/odometry", interfaces::stateQos());
    controller_pub_ =
        player_.createPublisher<msg::ControllerStatus>("control/status", interfaces::stateQos());
    waypoint_pub_ =
        player_.createPublisher<msg::Waypoint>("planner/waypoint", interfaces::commandQos());
    map_pub_ = player_.createPublisher<msg::OctomapUpdate>("map/update", interfaces::mapQos());
    query_sub_ = player_.createSubscription<msg::PlannerQuery>(
        "mission/query", interfaces::commandQos(),
        std::function<void(const msg::PlannerQuery&)>(
            [this](const msg::PlannerQuery& q) { queries.push_back(q); }));
    request_sub_ = player_.createSubscription<msg::WaypointRequest>(
        "planner/waypoint_request", interfaces::commandQos(),
        std::function<void(const msg::WaypointRequest&)>(
            [this](const msg::WaypointRequest& r) { requests.push_back(r); }));
    command_sub_ = player_.createSubscription<msg::ControllerCommand>(
        "control/waypoint", interfaces::commandQos(),
        std::function<void(const msg::ControllerCommand&)>([this](const msg::ControllerCommand& c) {
          commands.push_back(c);
          controller.active_command_id(c.command_id());  // as a controller does
        }));
    status_sub_ = player_.createSubscription<msg::MissionStatus>(
        "mission/status", interfaces::latchedStateQos(),
        std::function<void(const msg::MissionStatus&)>(
            [this](const msg::MissionStatus& s) { statuses.push_back(s); }));
    start_client_ =
        player_.createClient<msg::StartMissionRequest, msg::StartMissionReply>("mission/start");
    abort_client_ = player_.createClient<msg::TriggerRequest, msg::TriggerReply>("mission/abort");
    odometry_timer_ = player_.createTimer(0.05, [this] {
      if (publish_odometry) publishOdometry();
    });
    controller_timer_ = player_.createTimer(0.1, [this] { controller_pub_->publish(controller); });
    controller.state(msg::CONTROLLER_STATE_IDLE);
    executor_.add(mission_node_);
    executor_.add(player_);
    if (before_activate) before_activate(mission_node_);
    mission.activate();
  }

  ~MissionHarness() {
    mission.deactivate();
    mission.cleanup();
  }

  bool spinUntil(const std::function<bool()>& done, std::chrono::seconds timeout = 10s) {
    return executor_.spinUntil(done, timeout);
  }

  /// Every endpoint of the player matched with the mission component's.
  bool discovered() {
    return spinUntil([&] {
      return odometry_pub_->matchedSubscriptions() > 0 &&
             controller_pub_->matchedSubscriptions() > 0 &&
             waypoint_pub_->matchedSubscriptions() > 0 && map_pub_->matchedSubscriptions() > 0 &&
             query_sub_->matchedPublishers() > 0 && request_sub_->matchedPublishers() > 0 &&
             command_sub_->matchedPublishers() > 0 && status_sub_->matchedPublishers() > 0 &&
             start_client_->serviceReady() && abort_client_->serviceReady();
    });
  }

  /// Calls a service from another thread while this one spins the executor.
  template <class Client, class Req, class Rep>
  interfaces::CallStatus call(Client& client, const Req& request, Rep* reply) {
    std::atomic<bool> done{false};
    interfaces::CallStatus status = interfaces::CallStatus::TIMEOUT;
    std::thread caller([&] {
      status = client.call(request, reply, 10s);
      done = true;
    });
    spinUntil([&] { return done.load(); }, 15s);
    caller.join();
    return status;
  }

  msg::StartMissionReply start(const std::string& mission_id,
                               const std::vector<msg::PlannerQuery>& plan) {
    msg::StartMissionRequest request;
    request.mission_id(mission_id);
    request.queries(plan);
    msg::StartMissionReply reply;
    reply.status().code(msg::REPLY_CODE_INTERNAL_ERROR);
    reply.status().error_text("no reply");
    const auto status = call(*start_client_, request, &reply);
    EXPECT_EQ(status, interfaces::CallStatus::OK);
    return reply;
  }

  msg::TriggerReply abort() {
    msg::TriggerRequest request;
    request.command("test");
    msg::TriggerReply reply;
    reply.status().code(msg::REPLY_CODE_INTERNAL_ERROR);
    const auto status = call(*abort_client_, request, &reply);
    EXPECT_EQ(status, interfaces::CallStatus::OK);
    return reply;
  }

  void publishWaypoint(const msg::Waypoint& waypoint) { waypoint_pub_->publish(waypoint); }
  void publishMap(const msg::OctomapUpdate& update) { map_pub_->publish(update); }

  /// The newest status of `mission_id` received, if any.
  std::optional<msg::MissionStatus> statusOf(const std::string& mission_id) const {
    for (auto it = statuses.rbegin(); it != statuses.rend(); ++it) {
      if (it->mission_id() == mission_id) return *it;
    }
    return std::nullopt;
  }
  bool reachesState(const std::string& mission_id, msg::MissionState state,
                    std::chrono::seconds timeout = 10s) {
    return spinUntil(
        [&] {
          const auto status = statusOf(mission_id);
          return status && status->state() == state;
        },
        timeout);
  }

  /// Waits for the mission's first query and its waypoint request, and answers it with a
  /// waypoint at `position`; returns the waypoint (query_id 0 when nothing came).
  msg::Waypoint answerFirstRequest(const Eigen::Vector3d& position, bool is_final) {
    msg::Waypoint waypoint;
    if (!spinUntil([&] { return !queries.empty() && !requests.empty(); })) return waypoint;
    waypoint.waypoint_id(1);
    waypoint.query_id(requests.back().query_id());
    waypoint.position(point(position));
    waypoint.heading(0.0);
    waypoint.speed(0.6);
    waypoint.tolerance(0.5);
    waypoint.is_final(is_final);
    publishWaypoint(waypoint);
    return waypoint;
  }

  /// The first command of `mode` received, if any.
  std::optional<msg::ControllerCommand> commandOf(msg::ControlMode mode) const {
    for (const auto& command : commands) {
      if (command.mode() == mode) return command;
    }
    return std::nullopt;
  }

  MissionComponent mission;
  Eigen::Vector3d vehicle{0.0, 0.0, 5.0};
  bool publish_odometry = true;
  msg::ControllerStatus controller;
  std::vector<msg::PlannerQuery> queries;
  std::vector<msg::WaypointRequest> requests;
  std::vector<msg::ControllerCommand> commands;
  std::vector<msg::MissionStatus> statuses;
  Node& player() { return player_; }
  /// One odometry message at `vehicle` (callable from any thread).
  void publishOdometryNow() { publishOdometry(); }

 private:
  void publishOdometry() {
    msg::Odometry odometry;
    odometry.header().frame_id("world");
    odometry.child_frame_id("base_link");
    odometry.pose().pose().position(point(vehicle));
    odometry.pose().pose().orientation().w(1.0);
    odometry.altitude(-1.0);
    odometry_pub_->publish(odometry);
  }

  Node mission_node_;
  Node player_;
  interfaces::Executor executor_;
  std::shared_ptr<interfaces::Publisher<msg::Odometry>> odometry_pub_;
  std::shared_ptr<interfaces::Publisher<msg::ControllerStatus>> controller_pub_;
  std::shared_ptr<interfaces::Publisher<msg::Waypoint>> waypoint_pub_;
  std::shared_ptr<interfaces::Publisher<msg::OctomapUpdate>> map_pub_;
  std::shared_ptr<interfaces::Subscription<msg::PlannerQuery>> query_sub_;
  std::shared_ptr<interfaces::Subscription<msg::WaypointRequest>> request_sub_;
  std::shared_ptr<interfaces::Subscription<msg::ControllerCommand>> command_sub_;
  std::shared_ptr<interfaces::Subscription<msg::MissionStatus>> status_sub_;
  std::shared_ptr<interfaces::Client<msg::StartMissionRequest, msg::StartMissionReply>>
      start_client_;
  std::shared_ptr<interfaces::Client<msg::TriggerRequest, msg::TriggerReply>> abort_client_;
  std::shared_ptr<interfaces::Timer> odometry_timer_;
  std::shared_ptr<interfaces::Timer> controller_timer_;
};

// ---- (a) stale navigation -----------------------------------------------------------------

struct Vendors {
  Vendor mission;
  Vendor player;
  int domain;
};
void PrintTo(const Vendors& v, std::ostream* out) {
  auto name = [](Vendor vendor) { return vendor == Vendor::CYCLONEDDS ? "cyclonedds" : "fastdds"; };
  *out << "mission on " << name(v.mission) << ", player on " << name(v.player) << ", domain "
       << v.domain;
}

class StaleNavigationTest : public ::testing::TestWithParam<Vendors> {};

TEST_P(StaleNavigationTest, HoldsDepthAndWaitsForNavigation) {
  MissionHarness harness(GetParam().mission, GetParam().player, GetParam().domain);
  ASSERT_TRUE(harness.discovered());

  const msg::StartMissionReply reply = harness.start("stale", {queryTo({20, 0, 5})});
  ASSERT_EQ(reply.status().code(), msg::REPLY_CODE_OK) << reply.status().error_text();
  EXPECT_EQ(reply.mission_id(), "stale");

  // The query starts from the vehicle; its waypoint becomes the controller's waypoint.
  const msg::Waypoint waypoint = harness.answerFirstRequest({6, 0, 5}, false);
  ASSERT_NE(waypoint.query_id(), 0u) << "no query / waypoint request";
  EXPECT_EQ(vector(harness.queries.front().start().position()), Eigen::Vector3d(0, 0, 5));
  EXPECT_EQ(harness.requests.front().reached_waypoint_id(), 0u);
  ASSERT_TRUE(harness.spinUntil([&] {
    return harness.commandOf(msg::CONTROL_MODE_WAYPOINT).has_value();
  })) << "no WAYPOINT command";
  const msg::ControllerCommand command = *harness.commandOf(msg::CONTROL_MODE_WAYPOINT);
  EXPECT_EQ(vector(command.position()), Eigen::Vector3d(6, 0, 5));
  EXPECT_EQ(command.surge_speed(), 0.6);
  EXPECT_EQ(command.tolerance(), 0.5);
  ASSERT_TRUE(harness.reachesState("stale", msg::MISSION_STATE_EXECUTING));

  // The vehicle closes in, deeper: the early request for the next waypoint shows the mission
  // has this position. Then navigation stops.
  harness.vehicle = {5.0, 0.0, 6.0};  // 1.41 m from the waypoint
  ASSERT_TRUE(harness.spinUntil([&] {
    return harness.requests.back().reached_waypoint_id() == waypoint.waypoint_id();
  })) << "no early waypoint request";
  harness.publish_odometry = false;

  ASSERT_TRUE(harness.reachesState("stale", msg::MISSION_STATE_RECOVERING))
      << "still " << toString(harness.statusOf("stale").value_or(msg::MissionStatus()).state());
  EXPECT_CONTAINS(harness.statusOf("stale")->message(), "navigation stale");
  ASSERT_TRUE(harness.spinUntil([&] {
    return harness.commandOf(msg::CONTROL_MODE_SETPOINT).has_value();
  })) << "no hold command";
  const msg::ControllerCommand hold = harness.commands.back();
  EXPECT_EQ(hold.mode(), msg::CONTROL_MODE_SETPOINT);
  EXPECT_EQ(hold.surge_speed(), 0.0);
  EXPECT_EQ(hold.depth(), 6.0);  // the last depth navigation gave
  EXPECT_GT(hold.command_id(), command.command_id());
  EXPECT_EQ(harness.mission.status().state(), msg::MISSION_STATE_RECOVERING);
}

INSTANTIATE_TEST_SUITE_P(Vendors, StaleNavigationTest,
                         ::testing::Values(Vendors{Vendor::CYCLONEDDS, Vendor::FASTDDS, 151},
                                           Vendors{Vendor::FASTDDS, Vendor::CYCLONEDDS, 152}),
                         [](const ::testing::TestParamInfo<Vendors>& info) {
                           return std::string(info.param.mission == Vendor::CYCLONEDDS
                                                  ? "MissionOnCyclone"
                                                  : "MissionOnFastdds");
                         });

// Navigation that keeps arriving while the executor is busy elsewhere (components composed in
// one process share its thread) is not stale: mission campaigns on a loaded machine aborted
// with "navigation stale" after a long callback, the tick running before the queued odometry.
TEST(MissionComponentTest, NavigationArrivingWhileTheExecutorIsBusyIsNotStale) {
  // A callback of the mission's node that runs after its odometry and before its tick (as a
  // long map update or log write would) holds the executor for three odometry_timeouts (0.5 s
  // each), once it is asked to.
  std::atomic<bool> block{false};
  std::atomic<bool> blocked{false};
  std::shared_ptr<interfaces::Timer> blocker;
  MissionHarness harness(Vendor::CYCLONEDDS, Vendor::FASTDDS, 156, {}, [&](Node& node) {
    blocker = node.createTimer(0.01, [&] {
      if (!block || blocked) return;
      std::this_thread::sleep_for(1500ms);
      blocked = true;
    });
  });
  ASSERT_TRUE(harness.discovered());
  ASSERT_EQ(harness.start("busy", {queryTo({20, 0, 5})}).status().code(), msg::REPLY_CODE_OK);
  ASSERT_NE(harness.answerFirstRequest({6, 0, 5}, false).query_id(), 0u);
  ASSERT_TRUE(harness.reachesState("busy", msg::MISSION_STATE_EXECUTING));

  // Navigation now comes from a thread of its own (a sensor process), every 50 ms.
  harness.publish_odometry = false;
  std::atomic<bool> publishing{true};
  std::thread navigation([&] {
    while (publishing) {
      harness.publishOdometryNow();
      std::this_thread::sleep_for(50ms);
    }
  });
  block = true;
  harness.spinUntil([&] { return blocked.load(); });
  harness.spinUntil([] { return false; }, 1s);  // ticks after the block
  publishing = false;
  navigation.join();
  EXPECT_TRUE(blocked);
  EXPECT_EQ(harness.mission.status().state(), msg::MISSION_STATE_EXECUTING)
      << harness.mission.status().message();

  // Without navigation it still goes stale: the freshness is the arrival's, not the tick's.
  ASSERT_TRUE(harness.reachesState("busy", msg::MISSION_STATE_RECOVERING));
  EXPECT_CONTAINS(harness.statusOf("busy")->message(), "navigation stale");
  blocker->cancel();
}

// ---- (b) goal inside a known obstacle -------------------------------------------------------

/// A FULL map update (OctoMap binary) as the mapping component publishes it.
msg::OctomapUpdate fullMap(const octomap::OcTree& tree, uint64_t sequence) {
  std::ostringstream stream;
  tree.writeBinaryConst(stream);
  const std::string data = stream.str();
  msg::OctomapUpdate update;
  update.header().frame_id("world");
  update.map_id("octomap");
  update.sequence_number(sequence);
  update.base_sequence(0);
  update.kind(msg::OCTOMAP_UPDATE_FULL);
  update.encoding(msg::OCTOMAP_ENCODING_BINARY);
  update.tree_type(tree.getTreeType());
  update.resolution(tree.getResolution());
  double x0, y0, z0, x1, y1, z1;
  tree.getMetricMin(x0, y0, z0);
  tree.getMetricMax(x1, y1, z1);
  update.changed_min(point({x0, y0, z0}));
  update.changed_max(point({x1, y1, z1}));
  update.data(std::vector<uint8_t>(data.begin(), data.end()));
  return update;
}

TEST(MissionComponentTest, GoalInsideAKnownObstacleAndOverlongIdAreRefused) {
  MissionHarness harness(Vendor::FASTDDS, Vendor::CYCLONEDDS, 153);
  harness.publish_odometry = false;  // a start accepted before the map stays in readiness
  ASSERT_TRUE(harness.discovered());
  const Eigen::Vector3d rock(10.25, 0.25, 5.25);
  octomap::OcTree map(0.5);
  map.updateNode(octomap::point3d(rock.x(), rock.y(), rock.z()), true);
  harness.publishMap(fullMap(map, 1));

  // The map and the request travel on different topics: until the map is in, a start is
  // accepted (and aborted here again); once it is, the goal is refused.
  msg::StartMissionReply reply;
  int accepted_before_the_map = 0;
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (std::chrono::steady_clock::now() < deadline) {
    reply = harness.start("into-rock", {queryTo(rock)});
    if (reply.status().code() != msg::REPLY_CODE_OK) break;
    ++accepted_before_the_map;
    ASSERT_EQ(harness.abort().status().code(), msg::REPLY_CODE_OK);
  }
  EXPECT_EQ(reply.status().code(), msg::REPLY_CODE_INVALID_ARGUMENT)
      << "accepted " << accepted_before_the_map << " times";
  RecordProperty("accepted_before_the_map", accepted_before_the_map);
  EXPECT_CONTAINS(reply.status().error_text(), "inside a known obstacle");
  EXPECT_CONTAINS(reply.status().error_text(), "(10.25, 0.25, 5.25)");
  EXPECT_CONTAINS(reply.status().error_text(), "mission/start: query");

  // Refused means nothing started; a goal clear of the rock is accepted with the same map.
  EXPECT_NE(harness.mission.status().state(), msg::MISSION_STATE_CHECKING_READINESS);
  EXPECT_TRUE(harness.commands.empty());
  // An id longer than a DDS key holds could not be published on mission/status.
  const msg::StartMissionReply long_id =
      harness.start(std::string(300, 'm'), {queryTo({14, 0, 5})});
  EXPECT_EQ(long_id.status().code(), msg::REPLY_CODE_INVALID_ARGUMENT);
  EXPECT_CONTAINS(long_id.status().error_text(), "mission_id: at most 255 bytes");
  const msg::StartMissionReply clear = harness.start("clear", {queryTo({14, 0, 5})});
  EXPECT_EQ(clear.status().code(), msg::REPLY_CODE_OK) << clear.status().error_text();
}

// ---- (c, d) abort, and the latched final status ------------------------------------------

TEST(MissionComponentTest, AbortStopsARunningMissionAndIsRefusedWhenIdle) {
  MissionHarness harness(Vendor::CYCLONEDDS, Vendor::FASTDDS, 154);
  ASSERT_TRUE(harness.discovered());

  const msg::TriggerReply idle = harness.abort();
  EXPECT_EQ(idle.status().code(), msg::REPLY_CODE_REJECTED);
  EXPECT_CONTAINS(idle.status().error_text(), "no mission is running");

  ASSERT_EQ(harness.start("aborted", {queryTo({20, 0, 5})}).status().code(), msg::REPLY_CODE_OK);
  ASSERT_NE(harness.answerFirstRequest({6, 0, 5}, false).query_id(), 0u);
  ASSERT_TRUE(harness.reachesState("aborted", msg::MISSION_STATE_EXECUTING));

  // A second start while it runs is refused with the reason.
  const msg::StartMissionReply second = harness.start("second", {queryTo({1, 0, 5})});
  EXPECT_EQ(second.status().code(), msg::REPLY_CODE_REJECTED);
  EXPECT_CONTAINS(second.status().error_text(), "mission 'aborted' is EXECUTING");

  const msg::TriggerReply stopped = harness.abort();
  EXPECT_EQ(stopped.status().code(), msg::REPLY_CODE_OK) << stopped.status().error_text();
  EXPECT_CONTAINS(stopped.message(), "'aborted'");
  ASSERT_TRUE(harness.reachesState("aborted", msg::MISSION_STATE_ABORTED));
  EXPECT_CONTAINS(harness.statusOf("aborted")->message(), "aborted by request (test)");
  ASSERT_TRUE(
      harness.spinUntil([&] { return harness.commandOf(msg::CONTROL_MODE_SETPOINT).has_value(); }));
  EXPECT_EQ(harness.commands.back().surge_speed(), 0.0);
  EXPECT_EQ(harness.commands.back().depth(), 5.0);

  EXPECT_EQ(harness.abort().status().code(), msg::REPLY_CODE_REJECTED);  // over already

  // (d) A subscriber that joins after the end still gets the final status, from the
  // transient-local writer (status_rate 0.01: no periodic status within this test).
  std::vector<msg::MissionStatus> late;
  auto late_sub = harness.player().createSubscription<msg::MissionStatus>(
      "mission/status", interfaces::latchedStateQos(),
      std::function<void(const msg::MissionStatus&)>(
          [&](const msg::MissionStatus& s) { late.push_back(s); }));
  ASSERT_TRUE(harness.spinUntil([&] {
    for (const auto& s : late) {
      if (s.mission_id() == "aborted") return true;
    }
    return false;
  })) << late.size()
      << " statuses for the late joiner";
  for (const auto& s : late) {
    if (s.mission_id() != "aborted") continue;
    EXPECT_EQ(s.state(), msg::MISSION_STATE_ABORTED);
    EXPECT_CONTAINS(s.message(), "aborted by request");
  }
}

// ---- (e) the mission log ------------------------------------------------------------------

std::string readFile(const std::filesystem::path& path) {
  std::ifstream file(path);
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

TEST(MissionComponentTest, LogIsCompleteWhenTheMissionEnds) {
  const std::filesystem::path log_dir = ::testing::TempDir() + "mission_component_test_log";
  std::filesystem::remove_all(log_dir);
  MissionHarness harness(Vendor::FASTDDS, Vendor::CYCLONEDDS, 155,
                         {"log_dir:=" + log_dir.string(), "recovery_hold:=0.3"});
  ASSERT_TRUE(harness.discovered());

  const Eigen::Vector3d goal(3, 0, 5);
  ASSERT_EQ(harness.start("logged", {queryTo(goal)}).status().code(), msg::REPLY_CODE_OK);
  const msg::Waypoint first = harness.answerFirstRequest({1, 0, 5}, /*is_final=*/false);
  ASSERT_NE(first.query_id(), 0u);
  ASSERT_TRUE(
      harness.spinUntil([&] { return harness.commandOf(msg::CONTROL_MODE_WAYPOINT).has_value(); }));
  // A safety manoeuvre interrupts the query: the mission recovers and re-issues it.
  harness.controller.safety_maneuver(true);
  harness.controller.state(msg::CONTROLLER_STATE_SAFETY_MANEUVER);
  harness.controller.safety_reason(msg::SAFETY_REASON_MIN_ALTITUDE);
  harness.controller.safety_text("altitude 0.6 m < min_altitude 1 m; ascending");
  ASSERT_TRUE(harness.reachesState("logged", msg::MISSION_STATE_RECOVERING));
  harness.controller.safety_maneuver(false);
  harness.controller.state(msg::CONTROLLER_STATE_IDLE);
  harness.controller.safety_reason(msg::SAFETY_REASON_NONE);
  harness.controller.safety_text("");
  ASSERT_TRUE(harness.spinUntil([&] { return harness.queries.size() == 2; }));
  ASSERT_TRUE(harness.spinUntil(
      [&] { return harness.requests.back().query_id() == harness.queries.back().query_id(); }));
  const msg::Waypoint waypoint = harness.answerFirstRequest(goal, /*is_final=*/true);
  ASSERT_NE(waypoint.query_id(), first.query_id());
  ASSERT_TRUE(harness.spinUntil([&] {
    return !harness.commands.empty() &&
           harness.commands.back().mode() == msg::CONTROL_MODE_WAYPOINT;
  }));
  // The controller reports the waypoint reached.
  harness.controller.active_command_id(harness.commands.back().command_id());
  harness.controller.state(msg::CONTROLLER_STATE_HOLDING);
  harness.controller.reached(true);
  ASSERT_TRUE(harness.reachesState("logged", msg::MISSION_STATE_SUCCEEDED));
  EXPECT_EQ(harness.statusOf("logged")->queries_succeeded(), 1u);
  EXPECT_EQ(harness.statusOf("logged")->recoveries(), 1u);
  ASSERT_TRUE(harness.spinUntil([&] {
    return harness.commands.back().mode() == msg::CONTROL_MODE_HOLD;  // the final hold
  }));

  // The log is closed before the final status goes out.
  for (const char* name : {"events.csv", "waypoints.csv", "mission.yaml", "status.txt"}) {
    EXPECT_TRUE(std::filesystem::exists(log_dir / name)) << name;
  }
  const std::string status = readFile(log_dir / "status.txt");
  EXPECT_CONTAINS(status, "mission_id: logged\n");
  EXPECT_CONTAINS(status, "state: SUCCEEDED\n");
  EXPECT_CONTAINS(status, "queries_succeeded: 1\n");
  EXPECT_CONTAINS(status, "waypoints_received: 2\n");
  EXPECT_CONTAINS(status, "recoveries: 1\n");
  const std::string events = readFile(log_dir / "events.csv");
  EXPECT_EQ(events.rfind("t,event,", 0), 0u) << events;
  EXPECT_CONTAINS(events, "EXECUTING/waypoint");
  EXPECT_CONTAINS(events, ",RECOVERY_START,0,");
  EXPECT_CONTAINS(events, "recovery 1/3 of query 1 after MIN_ALTITUDE: altitude 0.6 m");
  EXPECT_CONTAINS(events, "RECOVERING/controller");
  EXPECT_CONTAINS(events, ",RECOVERY_REISSUE,0,");
  EXPECT_CONTAINS(events, "SUCCEEDED/");
  const std::string waypoints = readFile(log_dir / "waypoints.csv");
  std::ostringstream line;
  line << "," << waypoint.query_id() << ",1,3,0,5,1\n";
  EXPECT_CONTAINS(waypoints, line.str());
  const MissionPlan logged = loadMissionFile((log_dir / "mission.yaml").string());
  ASSERT_EQ(logged.queries.size(), 1u);
  EXPECT_EQ(logged.queries[0].goal, goal);
  EXPECT_EQ(logged.queries[0].goal_tolerance, 1.0);
  std::filesystem::remove_all(log_dir);
}

// A handler restarted within its launch finds progress.yaml and goes on with the mission: the
// query in progress again, with ids after the ones it had sent, the log appended to. The
// progress of another launch is left alone.
MissionProgress progressOf(const std::string& launch_id) {
  MissionProgress progress;
  progress.launch_id = launch_id;
  progress.mission_id = "resumed";
  progress.state = msg::MISSION_STATE_EXECUTING;
  progress.query_index = 0;
  progress.next_query_id = 7;
  progress.next_command_id = 20;
  progress.waypoints_received = 4;
  progress.plan.name = "resumed";
  progress.plan.queries.push_back(fromPlannerQuery(queryTo({3, 0, 5}), 0));
  return progress;
}

TEST(MissionComponentTest, RestartedHandlerResumesItsLaunchsMission) {
  const std::filesystem::path log_dir = ::testing::TempDir() + "mission_component_test_resume";
  std::filesystem::remove_all(log_dir);
  std::filesystem::create_directories(log_dir);
  writeProgress(log_dir / "progress.yaml", progressOf("launch-157"));
  std::ofstream(log_dir / "events.csv")
      << "t,event,query_index,query_id,waypoint_id,x,y,z,detail\n1,EXECUTING/waypoint,0,6,3,0";
  ::setenv("AUV_LAUNCH_ID", "launch-157", 1);
  {
    MissionHarness harness(Vendor::CYCLONEDDS, Vendor::FASTDDS, 157,
                           {"log_dir:=" + log_dir.string()});
    ASSERT_TRUE(harness.discovered());
    ASSERT_TRUE(harness.reachesState("resumed", msg::MISSION_STATE_WAITING_FOR_WAYPOINT));
    ASSERT_TRUE(harness.spinUntil([&] { return !harness.queries.empty(); }));
    EXPECT_EQ(harness.queries.front().query_id(), 7u);
    EXPECT_EQ(harness.statusOf("resumed")->waypoints_received(), 4u);
    const msg::Waypoint waypoint = harness.answerFirstRequest({3, 0, 5}, /*is_final=*/true);
    ASSERT_TRUE(harness.spinUntil([&] {
      return !harness.commands.empty() &&
             harness.commands.back().mode() == msg::CONTROL_MODE_WAYPOINT;
    }));
    EXPECT_GE(harness.commands.back().command_id(), 20u);
    harness.controller.state(msg::CONTROLLER_STATE_HOLDING);
    harness.controller.reached(true);
    ASSERT_TRUE(harness.reachesState("resumed", msg::MISSION_STATE_SUCCEEDED));
  }
  ::unsetenv("AUV_LAUNCH_ID");
  const std::string events = readFile(log_dir / "events.csv");
  EXPECT_EQ(events.rfind("t,event,", 0), 0u) << events;
  EXPECT_CONTAINS(events, "\n1,EXECUTING/waypoint,0,6,3,0\n") << "the earlier log is kept whole";
  EXPECT_CONTAINS(events, ",RESUMED,");
  EXPECT_CONTAINS(events, "SUCCEEDED/");
  const std::optional<MissionProgress> final = readProgress(log_dir / "progress.yaml");
  ASSERT_TRUE(final.has_value());
  EXPECT_EQ(final->state, msg::MISSION_STATE_SUCCEEDED);
  EXPECT_EQ(final->launch_id, "launch-157");
  std::filesystem::remove_all(log_dir);
}

TEST(MissionComponentTest, ProgressOfAnotherLaunchIsNotResumed) {
  const std::filesystem::path log_dir = ::testing::TempDir() + "mission_component_test_other";
  std::filesystem::remove_all(log_dir);
  std::filesystem::create_directories(log_dir);
  writeProgress(log_dir / "progress.yaml", progressOf("an-older-launch"));
  ::setenv("AUV_LAUNCH_ID", "launch-158", 1);
  {
    MissionHarness harness(Vendor::FASTDDS, Vendor::CYCLONEDDS, 158,
                           {"log_dir:=" + log_dir.string()});
    ASSERT_TRUE(harness.discovered());
    harness.spinUntil([] { return false; }, 2s);
    EXPECT_FALSE(harness.statusOf("resumed").has_value());
    EXPECT_TRUE(harness.queries.empty());
  }
  ::unsetenv("AUV_LAUNCH_ID");
  std::filesystem::remove_all(log_dir);
}

TEST(MissionComponentTest, RegisteredAsMission) {
  EXPECT_NE(interfaces::ComponentRegistry::instance().find("mission"), nullptr);
}

}  // namespace
}  // namespace auv::mission
