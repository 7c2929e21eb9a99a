// Cross-vendor interoperability through the public API: every pairing of Fast DDS and
// Cyclone DDS (publisher vendor x subscriber vendor) exchanges messages with each QoS
// profile, a transient-local late joiner gets the last sample, keyed instances stay apart
// and request/reply works both ways. Real DDS on loopback; each test its own domain id.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <string>
#include <tuple>
#include <vector>

#include "auv/interfaces/executor.h"
#include "auv/interfaces/node.h"

namespace auv::interfaces {
namespace {

using namespace std::chrono_literals;

struct VendorPair {
  Vendor writer;
  Vendor reader;
  int index;  // selects the domain id, so concurrently running tests never share one
};

std::string pairName(const testing::TestParamInfo<VendorPair>& info) {
  return toString(info.param.writer) + "_to_" + toString(info.param.reader);
}

// Domain ids 10..59 are this binary's: one per test and vendor pair (ctest runs tests in
// parallel processes).
int domainFor(int test, const VendorPair& pair) { return 10 + test * 10 + pair.index; }

NodeOptions optionsFor(Vendor vendor, int domain) {
  NodeOptions options;
  options.vendor = vendor;
  options.domain_id = domain;
  return options;
}

class InteropTest : public testing::TestWithParam<VendorPair> {};

// Publishes until `received()` or timeout: discovery takes a moment and volatile readers
// miss what was sent before they matched.
template <class T>
bool publishUntil(Executor& executor, Publisher<T>& publisher, const T& message,
                  const std::function<bool()>& received) {
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (std::chrono::steady_clock::now() < deadline) {
    publisher.publish(message);
    if (executor.spinUntil(received, 50ms)) return true;
  }
  return false;
}

TEST_P(InteropTest, EveryProfileDeliversStringsAcrossVendors) {
  const int domain = domainFor(0, GetParam());
  Node pub_node("talker", optionsFor(GetParam().writer, domain));
  Node sub_node("listener", optionsFor(GetParam().reader, domain));
  Executor executor;
  executor.add(sub_node);
  for (const std::string& profile : qosProfileNames()) {
    SCOPED_TRACE(profile);
    const std::string topic = "/interop/" + profile;
    std::vector<std::string> got;
    auto sub = sub_node.createSubscription<msg::String>(
        topic, qosProfileByName(profile),
        std::function<void(const msg::String&)>(
            [&](const msg::String& m) { got.push_back(m.data()); }));
    auto pub = pub_node.createPublisher<msg::String>(topic, qosProfileByName(profile));
    msg::String message;
    message.data("hello " + profile);
    ASSERT_TRUE(publishUntil<msg::String>(executor, *pub, message, [&] { return !got.empty(); }));
    EXPECT_EQ(got.front(), "hello " + profile);
    // Matching is reported per side and may trail the first sample by a moment.
    EXPECT_TRUE(executor.spinUntil(
        [&] { return pub->matchedSubscriptions() == 1 && sub->matchedPublishers() == 1; }, 5s));
  }
}

TEST_P(InteropTest, LateJoinerGetsLastTransientLocalSamplePerInstance) {
  const int domain = domainFor(1, GetParam());
  Node pub_node("mission", optionsFor(GetParam().writer, domain));
  auto pub =
      pub_node.createPublisher<msg::MissionStatus>("/interop/mission_status", latchedStateQos());
  for (int i = 1; i <= 3; ++i) {
    for (const char* id : {"alpha", "bravo"}) {
      msg::MissionStatus status;
      status.mission_id(id);
      status.message(std::string(id) + " update " + std::to_string(i));
      pub->publish(status);
    }
  }
  // Only now does the subscriber of the other vendor exist.
  Node sub_node("late", optionsFor(GetParam().reader, domain));
  Executor executor;
  executor.add(sub_node);
  std::map<std::string, std::vector<std::string>> got;
  auto sub = sub_node.createSubscription<msg::MissionStatus>(
      "/interop/mission_status", latchedStateQos(),
      std::function<void(const msg::MissionStatus&)>(
          [&](const msg::MissionStatus& m) { got[m.mission_id()].push_back(m.message()); }));
  executor.spinUntil([&] { return got.size() == 2; }, 10s);
  executor.spinUntil([] { return false; }, 300ms);  // anything more would be a bug
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got["alpha"], std::vector<std::string>{"alpha update 3"});
  EXPECT_EQ(got["bravo"], std::vector<std::string>{"bravo update 3"});
}

TEST_P(InteropTest, LargeMessagesArriveIntact) {
  const int domain = domainFor(2, GetParam());
  Node pub_node("mapper", optionsFor(GetParam().writer, domain));
  Node sub_node("planner", optionsFor(GetParam().reader, domain));
  Executor executor;
  executor.add(sub_node);
  std::vector<uint8_t> received;
  auto sub = sub_node.createSubscription<msg::OctomapUpdate>(
      "/interop/map", mapQos(),
      std::function<void(const msg::OctomapUpdate&)>(
          [&](const msg::OctomapUpdate& m) { received = m.data(); }));
  auto pub = pub_node.createPublisher<msg::OctomapUpdate>("/interop/map", mapQos());
  msg::OctomapUpdate update;
  std::vector<uint8_t> data(1 << 20);
  for (size_t i = 0; i < data.size(); ++i) data[i] = static_cast<uint8_t>(i * 7 + (i >> 9));
  update.data(data);
  // Once: the `map` profile is reliable and transient local, so the sample reaches the
  // reader whenever it matches (repeating would replace a sample still being repaired).
  pub->publish(update);
  ASSERT_TRUE(executor.spinUntil([&] { return !received.empty(); }, 20s));
  EXPECT_EQ(received, data);
}

TEST_P(InteropTest, RequestReplyRoundTripAcrossVendors) {
  const int domain = domainFor(3, GetParam());
  // GetParam().writer hosts the client, .reader the service.
  Node client_node("client", optionsFor(GetParam().writer, domain));
  Node server_node("server", optionsFor(GetParam().reader, domain));
  auto service = server_node.createService<msg::TriggerRequest, msg::TriggerReply>(
      "/interop/trigger", [](const msg::TriggerRequest& req, msg::TriggerReply& rep) {
        if (req.command() == "explode") throw std::invalid_argument("command 'explode' refused");
        rep.message("did " + req.command());
      });
  Executor executor;
  executor.add(server_node);
  std::thread spinner([&] { executor.spin(); });
  struct Join {
    Executor& e;
    std::thread& t;
    ~Join() {
      e.shutdown();
      t.join();
    }
  } join{executor, spinner};
  auto client =
      client_node.createClient<msg::TriggerRequest, msg::TriggerReply>("/interop/trigger");
  ASSERT_TRUE(client->waitForService(10s));
  msg::TriggerRequest request;
  msg::TriggerReply reply;
  for (int i = 0; i < 3; ++i) {
    request.command("step" + std::to_string(i));
    ASSERT_EQ(client->call(request, &reply, 10s), CallStatus::OK);
    EXPECT_EQ(reply.status().code(), msg::REPLY_CODE_OK);
    EXPECT_EQ(reply.message(), "did step" + std::to_string(i));
    EXPECT_EQ(reply.header().sequence_number(), static_cast<uint64_t>(i + 1));
  }
  request.command("explode");
  ASSERT_EQ(client->call(request, &reply, 10s), CallStatus::OK);
  EXPECT_EQ(reply.status().code(), msg::REPLY_CODE_INVALID_ARGUMENT);
  EXPECT_EQ(reply.status().error_text(), "command 'explode' refused");
  EXPECT_EQ(service->served(), 4u);  // resent requests were answered from the cache
}

INSTANTIATE_TEST_SUITE_P(AllPairs, InteropTest,
                         testing::Values(VendorPair{Vendor::CYCLONEDDS, Vendor::CYCLONEDDS, 0},
                                         VendorPair{Vendor::FASTDDS, Vendor::FASTDDS, 1},
                                         VendorPair{Vendor::FASTDDS, Vendor::CYCLONEDDS, 2},
                                         VendorPair{Vendor::CYCLONEDDS, Vendor::FASTDDS, 3}),
                         pairName);

TEST(ClientTest, CallWithoutServiceReportsNoService) {
  Node node("lonely", optionsFor(Vendor::CYCLONEDDS, 50));
  auto client = node.createClient<msg::TriggerRequest, msg::TriggerReply>("/nobody/home");
  msg::TriggerReply reply;
  EXPECT_EQ(client->call(msg::TriggerRequest(), &reply, 300ms), CallStatus::NO_SERVICE);
}

TEST(TopicNameTest, InvalidNamesAreRejectedWithTheName) {
  EXPECT_EQ(toDdsTopicName("/nav/odometry"), "nav/odometry");
  EXPECT_EQ(toDdsTopicName("chatter"), "chatter");
  EXPECT_THROW(toDdsTopicName("/"), std::invalid_argument);
  EXPECT_THROW(toDdsTopicName("bad topic"), std::invalid_argument);
  EXPECT_THROW(toDdsTopicName("a//b"), std::invalid_argument);
}

}  // namespace
}  // namespace auv::interfaces
