// Demo components composed in one process across vendors: the talker on Fast DDS, the
// listener on Cyclone DDS. Each test on its own domain id (160..169).
#include <gtest/gtest.h>

#include <fstream>

#include "auv/interfaces/executor.h"
#include "talker.h"

namespace auv::demo {
namespace {

using namespace std::chrono_literals;
using interfaces::Node;
using interfaces::NodeOptions;
using interfaces::nodeOptions;
using interfaces::Vendor;

TEST(DemoComponentsTest, ListenerOnCycloneHearsTalkerOnFastdds) {
  Node talker_node("talker", nodeOptions(Vendor::FASTDDS, 160, {"rate_hz:=50.0"}));
  Node listener_node("listener", nodeOptions(Vendor::CYCLONEDDS, 160));
  Talker talker;
  Listener listener;
  talker.configure(talker_node);
  listener.configure(listener_node);
  interfaces::Executor executor;
  executor.add(talker_node);
  executor.add(listener_node);
  talker.activate();
  listener.activate();
  ASSERT_TRUE(executor.spinUntil([&] { return listener.heard() >= 5; }, 10s));
  EXPECT_GE(talker.count(), listener.heard());

  // The reset service answers across vendors and really resets.
  Node client_node("operator", nodeOptions(Vendor::CYCLONEDDS, 160));
  auto client = client_node.createClient<msg::TriggerRequest, msg::TriggerReply>("talker/reset");
  msg::TriggerReply reply;
  std::thread spinner([&] { executor.spin(); });
  const auto status = client->call(msg::TriggerRequest(), &reply, 10s);
  executor.shutdown();
  spinner.join();
  ASSERT_EQ(status, interfaces::CallStatus::OK);
  EXPECT_EQ(reply.status().code(), msg::REPLY_CODE_OK);
  EXPECT_EQ(reply.message().rfind("count was ", 0), 0u) << reply.message();
  EXPECT_LT(talker.count(), 5u);
  talker.deactivate();
}

TEST(DemoComponentsTest, BadParameterNamesParameterAndSource) {
  Node node("talker", nodeOptions(Vendor::CYCLONEDDS, 161, {"rate_hz:=-3"}));
  Talker talker;
  try {
    talker.configure(node);
    FAIL() << "configure accepted rate_hz -3";
  } catch (const interfaces::ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("rate_hz"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("-3"), std::string::npos) << e.what();
  }
}

TEST(DemoComponentsTest, BadParameterFileNamesTheFile) {
  const std::string path = testing::TempDir() + "demo_bad_params.yaml";
  std::ofstream(path) << "talker:\n  rate_hz: fast\n";
  NodeOptions options = nodeOptions(Vendor::CYCLONEDDS, 162);
  options.params_files = {path};
  Node node("talker", options);
  Talker talker;
  try {
    talker.configure(node);
    FAIL() << "configure accepted rate_hz 'fast'";
  } catch (const interfaces::ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("rate_hz"), std::string::npos) << e.what();
  }
}

TEST(DemoComponentsTest, RegisteredUnderTheirNames) {
  EXPECT_NE(interfaces::ComponentRegistry::instance().find("demo_talker"), nullptr);
  EXPECT_NE(interfaces::ComponentRegistry::instance().find("demo_listener"), nullptr);
}

}  // namespace
}  // namespace auv::demo
