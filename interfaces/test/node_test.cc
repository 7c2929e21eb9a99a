// Node services other than transport: the simulation clock and timers on it, system timers,
// QoS overrides from parameters, the `log` topic, and errors at construction. Domains 60..66.
#include <gtest/gtest.h>

#include <chrono>

#include "auv/interfaces/executor.h"
#include "auv/interfaces/node.h"

namespace auv::interfaces {
namespace {

using namespace std::chrono_literals;

NodeOptions options(int domain, Vendor vendor, std::vector<std::string> overrides = {}) {
  NodeOptions o;
  o.domain_id = domain;
  o.vendor = vendor;
  o.overrides = std::move(overrides);
  return o;
}

msg::Clock clockAt(double seconds) {
  msg::Clock c;
  c.sim_time().sec(static_cast<int32_t>(seconds));
  c.sim_time().nanosec(static_cast<uint32_t>((seconds - static_cast<int32_t>(seconds)) * 1e9));
  return c;
}

class SimTimeTest : public testing::TestWithParam<Vendor> {};

TEST_P(SimTimeTest, TimersFollowTheSimulationClockNotTheWallClock) {
  const int domain = 60 + static_cast<int>(GetParam());
  // The simulator (other vendor) publishes `clock`; the node follows it.
  Node simulator("simulator", options(domain, GetParam() == Vendor::FASTDDS ? Vendor::CYCLONEDDS
                                                                            : Vendor::FASTDDS));
  auto clock_pub = simulator.createPublisher<msg::Clock>("clock", viewingQos());
  Node node("component", options(domain, GetParam(), {"use_sim_time:=true"}));
  EXPECT_EQ(node.clock().source(), Clock::Source::SIMULATION);
  EXPECT_EQ(node.clock().nowNs(), 0);
  int fired = 0;
  auto timer = node.createTimer(1.0, [&] { ++fired; });  // 1 s of simulated time
  Executor executor;
  executor.add(node);

  // Wait for the clock to arrive, starting at t = 100 s.
  ASSERT_TRUE(executor.spinUntil(
      [&] {
        clock_pub->publish(clockAt(100.0));
        return node.clock().nowNs() == 100'000'000'000LL;
      },
      10s));
  executor.spinUntil([] { return false; }, 300ms);  // wall time passes, simulated time not
  EXPECT_EQ(fired, 0);
  // 10 simulated seconds in 0.1 s steps, faster than real time: 10 firings.
  for (int step = 1; step <= 100; ++step) {
    clock_pub->publish(clockAt(100.0 + step * 0.1));
    const int64_t expected = 100'000'000'000LL + step * 100'000'000LL;
    ASSERT_TRUE(executor.spinUntil([&] { return node.clock().nowNs() >= expected - 1000; }, 5s))
        << "step " << step;
    executor.spinSome();  // the executor sees every 0.1 s step (missed periods are skipped)
  }
  EXPECT_EQ(fired, 10);
}

INSTANTIATE_TEST_SUITE_P(Vendors, SimTimeTest,
                         testing::Values(Vendor::CYCLONEDDS, Vendor::FASTDDS));

TEST(NodeTest, SystemTimerFiresAtItsPeriod) {
  Node node("ticker", options(63, Vendor::CYCLONEDDS));
  int fired = 0;
  auto timer = node.createTimer(0.02, [&] { ++fired; });
  Executor executor;
  executor.add(node);
  const auto start = std::chrono::steady_clock::now();
  executor.spinUntil([&] { return fired >= 10; }, 5s);
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(fired, 10);
  EXPECT_GE(elapsed, 10 * 0.02 - 0.005);  // never early: 10 periods must have passed
  timer->cancel();
  executor.spinUntil([] { return false; }, 100ms);
  EXPECT_EQ(fired, 10);
  EXPECT_THROW(node.createTimer(0.0, [] {}), std::invalid_argument);
}

TEST(NodeTest, QosProfileOfATopicIsOverriddenByParameter) {
  Node node("tuned", options(64, Vendor::CYCLONEDDS, {"qos.nav/odometry:=sensor_data"}));
  auto pub = node.createPublisher<msg::Odometry>("/nav/odometry", stateQos());
  EXPECT_EQ(pub->qos().name, "sensor_data");
  EXPECT_EQ(pub->qos().reliability, Reliability::BEST_EFFORT);
  auto other = node.createPublisher<msg::String>("/chatter", commandQos());
  EXPECT_EQ(other->qos().name, "command");
  Node bad("bad", options(64, Vendor::CYCLONEDDS, {"qos.chatter:=turbo"}));
  try {
    bad.createPublisher<msg::String>("chatter", commandQos());
    FAIL() << "unknown profile accepted";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("qos.chatter"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("turbo"), std::string::npos) << e.what();
  }
}

TEST(NodeTest, LogLinesArePublishedOnTheLogTopic) {
  Node node("chatty", options(65, Vendor::FASTDDS));
  Node reader("reader", options(65, Vendor::CYCLONEDDS));
  std::vector<std::string> lines;
  auto sub = reader.createSubscription<msg::LogEntry>(
      "log", latchedStateQos(),
      std::function<void(const msg::LogEntry&)>([&](const msg::LogEntry& e) {
        if (e.node_name() == "chatty" && e.level() == msg::LOG_LEVEL_WARN)
          lines.push_back(e.message());
      }));
  Executor executor;
  executor.add(reader);
  node.logger().warn("depth limit close: 48.5 m");
  node.logger().debug("not published below log_level");
  // Transient local: the line reaches the reader even if it matched after the write.
  ASSERT_TRUE(executor.spinUntil([&] { return !lines.empty(); }, 10s));
  EXPECT_EQ(lines, std::vector<std::string>{"depth limit close: 48.5 m"});
}

TEST(NodeTest, BadBuiltInParametersNameParameterAndValue) {
  try {
    Node node("n", options(66, Vendor::CYCLONEDDS, {"use_sim_time:=yes"}));
    FAIL() << "use_sim_time 'yes' accepted";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("use_sim_time"), std::string::npos) << e.what();
  }
  try {
    Node node("n", options(66, Vendor::CYCLONEDDS, {"log_level:=loud"}));
    FAIL() << "log_level 'loud' accepted";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("log_level"), std::string::npos) << e.what();
  }
  EXPECT_THROW(Node("", options(66, Vendor::CYCLONEDDS)), std::invalid_argument);
}

}  // namespace
}  // namespace auv::interfaces
