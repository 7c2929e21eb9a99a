// The `controller` component on real DDS: a harness node plays the navigation and the mission
// handler (and the simulator's clock). Cyclone DDS and Fast DDS, also mixed. One DDS domain per
// test that exchanges data (230-232, and 3 for the map test: with the default port mapping 232 is
// the highest domain id either vendor accepts). The parameter test sends nothing and shares 230.
#include "auv/control/components/controller_component.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <octomap/OcTree.h>

#include "auv/interfaces/executor.h"
#include "full_map_update.h"

namespace auv::control {
namespace {

using namespace std::chrono_literals;
using interfaces::Node;
using interfaces::NodeOptions;
using interfaces::nodeOptions;
using interfaces::Vendor;

// Publishes odometry (a vehicle at rest at `position`, heading north) and commands; records
// what the controller publishes and logs.
class Harness {
 public:
  Harness(Vendor vendor, int domain) : node_("harness", nodeOptions(vendor, domain)) {
    odometry_ = node_.createPublisher<msg::Odometry>("nav/odometry", interfaces::stateQos());
    commands_ =
        node_.createPublisher<msg::ControllerCommand>("control/waypoint", interfaces::commandQos());
    clock_ = node_.createPublisher<msg::Clock>("clock", interfaces::clockQos());
    map_ = node_.createPublisher<msg::OctomapUpdate>("map/update", interfaces::mapQos());
    thrusters_ = node_.createSubscription<msg::ThrusterSetpoints>(
        "control/thrusters", interfaces::sensorDataQos(),
        std::function<void(const msg::ThrusterSetpoints&)>([this](const msg::ThrusterSetpoints& m) {
          thrust = m;
          ++thrust_count;
        }));
    status_ = node_.createSubscription<msg::ControllerStatus>(
        "control/status", interfaces::stateQos(),
        std::function<void(const msg::ControllerStatus&)>([this](const msg::ControllerStatus& m) {
          status = m;
          ++status_count;
        }));
    interfaces::QosProfile log_qos = interfaces::latchedStateQos();
    log_qos.depth = 20;
    log_ = node_.createSubscription<msg::LogEntry>(
        "log", log_qos, std::function<void(const msg::LogEntry&)>([this](const msg::LogEntry& m) {
          if (m.node_name() == "controller") log.push_back(m.message());
        }));
    odometry_timer_ = node_.createTimer(0.05, [this] {
      if (publish_odometry) publishOdometry();
    });
  }

  Node& node() { return node_; }

  void publishOdometry() {
    msg::Odometry odom;
    odom.header().frame_id("world");
    odom.child_frame_id("base_link");
    odom.pose().pose().position().x(position.x());
    odom.pose().pose().position().y(position.y());
    odom.pose().pose().position().z(position.z());
    odom.pose().pose().orientation().w(1.0);
    odom.altitude(altitude);
    odometry_->publish(odom);
  }

  /// Publishes `tree` as the mapping component's FULL map update `sequence` (OctoMap binary).
  void publishMap(const octomap::OcTree& tree, uint64_t sequence) {
    map_->publish(test::fullMapUpdate(tree, sequence));
  }

  void send(uint64_t id, msg::ControlMode mode, const Eigen::Vector3d& target, double speed = 0.8,
            double tolerance = 1.0) {
    msg::ControllerCommand c;
    c.header().frame_id("world");
    c.command_id(id);
    c.mode(mode);
    c.position().x(target.x());
    c.position().y(target.y());
    c.position().z(target.z());
    c.surge_speed(speed);
    c.tolerance(tolerance);
    commands_->publish(c);
  }
  void send(const msg::ControllerCommand& c) { commands_->publish(c); }

  void publishClock(double seconds) {
    msg::Clock c;
    c.sim_time().sec(static_cast<int32_t>(seconds));
    c.sim_time().nanosec(static_cast<uint32_t>((seconds - std::floor(seconds)) * 1e9));
    clock_->publish(c);
  }

  bool connected() const {
    return odometry_->matchedSubscriptions() > 0 && commands_->matchedSubscriptions() > 0 &&
           thrusters_->matchedPublishers() > 0 && status_->matchedPublishers() > 0;
  }
  bool logged(const std::string& text) const {
    for (const auto& line : log) {
      if (line.find(text) != std::string::npos) return true;
    }
    return false;
  }

  Eigen::Vector3d position{0, 0, 2};
  double altitude = -1.0;  // m, as the DVL reports it; < 0 = no bottom lock
  bool publish_odometry = true;
  msg::ThrusterSetpoints thrust;
  int thrust_count = 0;
  msg::ControllerStatus status;
  int status_count = 0;
  std::vector<std::string> log;

 private:
  Node node_;
  std::shared_ptr<interfaces::Publisher<msg::Odometry>> odometry_;
  std::shared_ptr<interfaces::Publisher<msg::ControllerCommand>> commands_;
  std::shared_ptr<interfaces::Publisher<msg::Clock>> clock_;
  std::shared_ptr<interfaces::Publisher<msg::OctomapUpdate>> map_;
  std::shared_ptr<interfaces::Subscription<msg::ThrusterSetpoints>> thrusters_;
  std::shared_ptr<interfaces::Subscription<msg::ControllerStatus>> status_;
  std::shared_ptr<interfaces::Subscription<msg::LogEntry>> log_;
  std::shared_ptr<interfaces::Timer> odometry_timer_;
};

// The controller component and the harness spun by one executor.
struct Rig {
  Rig(Vendor controller_vendor, Vendor harness_vendor, int domain,
      std::vector<std::string> overrides = {})
      : controller_node("controller", nodeOptions(controller_vendor, domain, std::move(overrides))),
        harness(harness_vendor, domain) {
    component.configure(controller_node);
    executor.add(controller_node);
    executor.add(harness.node());
    component.activate();
  }
  ~Rig() {
    component.deactivate();
    component.cleanup();
  }
  // Spins until `done()`, running `each` (e.g. a publication) between spins; advances the
  // simulation clock by the wall time spun when `publish_clock`.
  bool spinUntil(const std::function<bool()>& done, const std::function<void()>& each = {},
                 std::chrono::nanoseconds timeout = 20s) {
    const auto start = std::chrono::steady_clock::now();
    auto last = start;
    while (std::chrono::steady_clock::now() - start < timeout) {
      if (done()) return true;
      if (each) each();
      if (publish_clock) {
        const auto now = std::chrono::steady_clock::now();
        sim_time += std::chrono::duration<double>(now - last).count();
        last = now;
        harness.publishClock(sim_time);
      }
      executor.spinOnce(20ms);
    }
    return done();
  }
  // Waits for the connection and for navigation to be in use (the status echoes its depth),
  // past any NAVIGATION_LOST from before the first odometry.
  void waitReady() {
    ASSERT_TRUE(spinUntil([&] { return harness.connected(); })) << "no DDS match";
    ASSERT_TRUE(spinUntil([&] {
      return harness.status_count > 0 && harness.status.depth() == harness.position.z() &&
             !harness.status.safety_maneuver();
    })) << "the controller never used the odometry";
  }
  // Sends until the status shows the command active (the first may precede the match).
  bool command(uint64_t id, msg::ControlMode mode, const Eigen::Vector3d& target) {
    return spinUntil([&] { return harness.status.active_command_id() == id; },
                     [&] { harness.send(id, mode, target); });  // repeats are ignored
  }
  // Lets `n` fresh thruster setpoints arrive.
  bool freshThrust(int n = 5) {
    const int start = harness.thrust_count;
    return spinUntil([&] { return harness.thrust_count >= start + n; });
  }

  Node controller_node;
  Harness harness;
  bool publish_clock = false;
  double sim_time = 1000.0;  // s
  ControllerComponent component;
  interfaces::Executor executor;
};

TEST(ControllerComponentTest, WaypointDrivesTheThrustersAndLostNavigationRaisesTheManoeuvre) {
  Rig rig(Vendor::CYCLONEDDS, Vendor::CYCLONEDDS, 230,
          {"controller.navigation_timeout:=0.5", "controller.safety_clear_time:=0.5"});
  rig.waitReady();

  // Straight ahead (north, same depth): both horizontal thrusters push forward alike.
  ASSERT_TRUE(rig.command(7, msg::CONTROL_MODE_WAYPOINT, {20, 0, 2}));
  ASSERT_TRUE(rig.freshThrust());
  EXPECT_EQ(rig.harness.status.state(), msg::CONTROLLER_STATE_ACTIVE);
  EXPECT_FALSE(rig.harness.status.reached());
  EXPECT_NEAR(rig.harness.status.distance_to_target(), 20.0, 1e-6);
  EXPECT_GT(rig.harness.thrust.port(), 0.3);
  EXPECT_GT(rig.harness.thrust.starboard(), 0.3);
  EXPECT_NEAR(rig.harness.thrust.port(), rig.harness.thrust.starboard(), 0.05);
  // At the target depth the vertical thruster only holds the buoyancy down (2 N of 25 N).
  EXPECT_NEAR(rig.harness.thrust.vertical(), 2.0 / 25.0, 0.03);
  EXPECT_EQ(rig.harness.thrust.header().frame_id(), "base_link");

  // To the east: turn to starboard, port pushes harder.
  ASSERT_TRUE(rig.command(8, msg::CONTROL_MODE_WAYPOINT, {0, 20, 2}));
  ASSERT_TRUE(rig.freshThrust());
  EXPECT_GT(rig.harness.thrust.port(), rig.harness.thrust.starboard() + 0.3);

  // Deeper target: the vertical thruster pushes down.
  ASSERT_TRUE(rig.command(9, msg::CONTROL_MODE_WAYPOINT, {20, 0, 6}));
  ASSERT_TRUE(rig.freshThrust());
  EXPECT_GT(rig.harness.thrust.vertical(), 0.9);

  // Navigation stops: the controller surfaces on its own.
  rig.harness.publish_odometry = false;
  ASSERT_TRUE(rig.spinUntil([&] { return rig.harness.status.safety_maneuver(); }));
  EXPECT_EQ(rig.harness.status.state(), msg::CONTROLLER_STATE_SAFETY_MANEUVER);
  EXPECT_EQ(rig.harness.status.safety_reason(), msg::SAFETY_REASON_NAVIGATION_LOST);
  EXPECT_NE(rig.harness.status.safety_text().find("navigation"), std::string::npos);
  EXPECT_EQ(rig.harness.status.active_command_id(), 9u);
  ASSERT_TRUE(rig.freshThrust());
  EXPECT_EQ(rig.harness.thrust.vertical(), -1.0);
  EXPECT_EQ(rig.harness.thrust.port(), 0.0);
  EXPECT_EQ(rig.harness.thrust.starboard(), 0.0);
  EXPECT_TRUE(rig.spinUntil([&] { return rig.harness.logged("NAVIGATION_LOST"); }));

  // Navigation back: the manoeuvre ends and the interrupted command is dropped.
  rig.harness.publish_odometry = true;
  ASSERT_TRUE(rig.spinUntil([&] { return !rig.harness.status.safety_maneuver(); }));
  EXPECT_EQ(rig.harness.status.state(), msg::CONTROLLER_STATE_IDLE);
}

// A roof of rock: occupied cells at depth 2-2.5 m over x in [-10, 10], y in [-3, 3].
octomap::OcTree ceiling() {
  octomap::OcTree tree(0.5);
  for (double x = -10; x <= 10; x += 0.5) {
    for (double y = -3; y <= 3; y += 0.5)
      tree.updateNode(octomap::point3d(x + 0.25, y + 0.25, 2.25), true);
  }
  return tree;
}

TEST(ControllerComponentTest, OverheadClearanceSeesRockAboveNotBesideNorUnknown) {
  const octomap::OcTree roof = ceiling();
  // Under the roof: from 5 m up to its deep face at 2.5 m.
  EXPECT_NEAR(ControllerComponent::overheadClearance(roof, {0, 0, 5}, 1.0), 2.5, 1e-6);
  // Beyond its edge by more than the radius: open (unknown counts as open).
  EXPECT_TRUE(std::isinf(ControllerComponent::overheadClearance(roof, {12.5, 0, 5}, 1.0)));
  // Above the roof, the rock is below: open.
  EXPECT_TRUE(std::isinf(ControllerComponent::overheadClearance(roof, {0, 0, 1.5}, 1.0)));
  // A wall 1.5 m beside the vehicle, up to the surface: beside, not above.
  octomap::OcTree wall(0.5);
  for (double z = 0; z < 8; z += 0.5) wall.updateNode(octomap::point3d(0.25, 1.75, z + 0.25), true);
  EXPECT_TRUE(std::isinf(ControllerComponent::overheadClearance(wall, {0.25, 0.25, 5}, 1.0)));
  EXPECT_NEAR(ControllerComponent::overheadClearance(wall, {0.25, 0.25, 5}, 1.6), 0.0, 1e-6);
  EXPECT_TRUE(
      std::isinf(ControllerComponent::overheadClearance(octomap::OcTree(0.5), {0, 0, 5}, 1.0)));
}

TEST(ControllerComponentTest, MapWithACeilingMakesTheManoeuvreBackAwayInsteadOfAscending) {
  Rig rig(Vendor::CYCLONEDDS, Vendor::FASTDDS, 3);
  rig.harness.position = {0, 0, 5};
  rig.waitReady();
  rig.harness.publishMap(ceiling(), 1);
  // The vehicle comes 5 m north under the roof: the controller keeps its trail.
  for (double x = 0.5; x <= 5.0; x += 0.5) {
    rig.harness.position.x() = x;
    const int count = rig.harness.status_count;
    ASSERT_TRUE(rig.spinUntil([&] { return rig.harness.status_count >= count + 1; }));
  }
  // Then the DVL sees rock 0.5 m below: MIN_ALTITUDE with rock 2.5 m above.
  rig.harness.altitude = 0.5;
  ASSERT_TRUE(rig.spinUntil([&] {
    return rig.harness.status.safety_text().find("backing away: rock 2.5 m above") !=
           std::string::npos;
  })) << rig.harness.status.safety_text();
  EXPECT_EQ(rig.harness.status.safety_reason(), msg::SAFETY_REASON_MIN_ALTITUDE);
  ASSERT_TRUE(rig.freshThrust());
  // Reversing south along the trail (heading north), never full up into the roof.
  EXPECT_LT(rig.harness.thrust.port(), -0.05);
  EXPECT_LT(rig.harness.thrust.starboard(), -0.05);
  EXPECT_GT(rig.harness.thrust.vertical(), -0.5);
  // Out from under the roof (the map says open above): it ascends.
  rig.harness.position.x() = 13.0;
  ASSERT_TRUE(rig.spinUntil([&] {
    return rig.harness.status.safety_text().find("; ascending") != std::string::npos;
  })) << rig.harness.status.safety_text();
  ASSERT_TRUE(rig.freshThrust());
  EXPECT_EQ(rig.harness.thrust.vertical(), -1.0);
  // Each change of action is logged.
  EXPECT_TRUE(rig.spinUntil([&] { return rig.harness.logged("backing away: rock 2.5 m above"); }));
  EXPECT_TRUE(rig.spinUntil([&] { return rig.harness.logged("; ascending"); }));
}

TEST(ControllerComponentTest, MalformedCommandsAreLoggedAndTheActiveOneKept) {
  // Controller on Fast DDS, harness on Cyclone DDS.
  Rig rig(Vendor::FASTDDS, Vendor::CYCLONEDDS, 231);
  rig.waitReady();
  ASSERT_TRUE(rig.command(1, msg::CONTROL_MODE_WAYPOINT, {20, 0, 2}));

  msg::ControllerCommand bad;
  bad.command_id(2);
  bad.mode(msg::CONTROL_MODE_WAYPOINT);
  bad.position().x(5);
  bad.surge_speed(std::nan(""));
  bad.tolerance(1.0);
  rig.harness.send(bad);
  bad.command_id(3);
  bad.surge_speed(0.5);
  bad.tolerance(-2.0);
  rig.harness.send(bad);
  bad.command_id(4);
  bad.tolerance(1.0);
  bad.mode(static_cast<msg::ControlMode>(42));
  rig.harness.send(bad);
  ASSERT_TRUE(rig.spinUntil([&] {
    return rig.harness.logged("surge_speed") && rig.harness.logged("tolerance") &&
           rig.harness.logged("mode: unknown value 42");
  })) << "log lines seen: "
      << rig.harness.log.size();
  EXPECT_TRUE(rig.harness.logged("command 2: surge_speed"));
  EXPECT_TRUE(rig.harness.logged("command 3: tolerance"));

  // Still on command 1, still running.
  ASSERT_TRUE(rig.freshThrust());
  EXPECT_EQ(rig.harness.status.active_command_id(), 1u);
  EXPECT_EQ(rig.harness.status.state(), msg::CONTROLLER_STATE_ACTIVE);
  EXPECT_GT(rig.harness.thrust.port(), 0.3);
}

TEST(ControllerComponentTest, MaxDepthManoeuvreInSimulationTimeOnFastdds) {
  Rig rig(Vendor::FASTDDS, Vendor::FASTDDS, 232,
          {"use_sim_time:=true", "controller.max_depth:=10.0"});
  rig.harness.position = {0, 0, 12};
  ASSERT_TRUE(rig.spinUntil([&] { return rig.harness.connected(); }));
  // No simulation time yet: no control steps.
  rig.spinUntil([] { return false; }, {}, 300ms);
  EXPECT_EQ(rig.harness.thrust_count, 0);

  rig.publish_clock = true;
  ASSERT_TRUE(rig.spinUntil(
      [&] { return rig.harness.status.safety_reason() == msg::SAFETY_REASON_MAX_DEPTH; }));
  EXPECT_TRUE(rig.harness.status.safety_maneuver());
  EXPECT_EQ(rig.harness.status.state(), msg::CONTROLLER_STATE_SAFETY_MANEUVER);
  EXPECT_NEAR(rig.harness.status.depth(), 12.0, 1e-9);
  EXPECT_NE(rig.harness.status.safety_text().find("max_depth 10"), std::string::npos)
      << rig.harness.status.safety_text();
  ASSERT_TRUE(rig.freshThrust());
  EXPECT_EQ(rig.harness.thrust.vertical(), -1.0);
  // Stamped with the simulation clock.
  const auto& stamp = rig.harness.thrust.header().stamp();
  const double seconds = stamp.sec() + stamp.nanosec() * 1e-9;
  EXPECT_GE(seconds, 1000.0);
  EXPECT_LE(seconds, rig.sim_time + 1e-6);
  // A command during the manoeuvre is refused, not executed.
  rig.harness.send(5, msg::CONTROL_MODE_WAYPOINT, {20, 0, 5});
  ASSERT_TRUE(rig.spinUntil([&] { return rig.harness.logged("refused"); }));
  EXPECT_NE(rig.harness.status.active_command_id(), 5u);
}

TEST(ControllerComponentTest, BadParametersNameTheParameter) {
  auto configureError = [](const std::string& assignment) -> std::string {
    Node node("controller_parameters", nodeOptions(Vendor::CYCLONEDDS, 230, {assignment}));
    ControllerComponent component;
    try {
      component.configure(node);
    } catch (const std::exception& e) {
      return e.what();
    }
    return "";
  };
  std::string error = configureError("controller.depth_kp:=-1.0");
  EXPECT_NE(error.find("controller.depth_kp"), std::string::npos) << error;
  error = configureError("controller.fault_action:=drift");
  EXPECT_NE(error.find("controller.fault_action"), std::string::npos) << error;
  error = configureError("controller.default_surge_speed:=1.5");  // above max_surge_speed
  EXPECT_NE(error.find("controller.default_surge_speed"), std::string::npos) << error;
  error = configureError("control_rate:=0");
  EXPECT_NE(error.find("control_rate"), std::string::npos) << error;
  EXPECT_EQ(configureError("controller.model.net_buoyancy:=-3.0"), "");
}

TEST(ControllerComponentTest, RegisteredAsController) {
  const auto* info = interfaces::ComponentRegistry::instance().find("controller");
  ASSERT_NE(info, nullptr);
  EXPECT_NE(info->description.find("control/thrusters"), std::string::npos);
}

}  // namespace
}  // namespace auv::control
