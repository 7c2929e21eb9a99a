// GraphInspector against real DDS traffic on loopback: talkers of each vendor, inspectors of
// each vendor, one DDS domain per test (100-150) so tests never see each other.
#include "auv/interfaces/graph.h"

#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <memory>
#include <string>
#include <tuple>

#include <gtest/gtest.h>

#include "auv/interfaces/backend.h"
#include "auv/msg/type_support.h"

namespace auv::interfaces {
namespace {

using std::chrono::milliseconds;

constexpr const char* kTopic = "/graph_test/chatter";
constexpr milliseconds kDiscoveryTimeout{5000};

// The demo string type when the message set has it, else any type of the set: the graph
// does not care which type it is, only that the announced name comes back.
const msg::TypeSupport& testType() {
  const msg::TypeSupport* type = msg::findType("auv::msg::String");
  if (type == nullptr) type = &msg::allTypes().at(0);
  return *type;
}

std::string hostName() {
  char host[256] = {0};
  gethostname(host, sizeof(host) - 1);
  return host;
}

// A writer profile far from every default, so the test sees it was really discovered.
QosProfile writerQos() {
  QosProfile q;
  q.reliability = Reliability::RELIABLE;
  q.durability = Durability::TRANSIENT_LOCAL;
  q.history = History::KEEP_LAST;
  q.depth = 7;
  q.deadline_s = 2.0;
  q.max_samples = 100;
  q.max_instances = 10;
  q.max_samples_per_instance = 10;
  return q;
}

QosProfile readerQos() {
  QosProfile q;
  q.reliability = Reliability::BEST_EFFORT;
  q.durability = Durability::VOLATILE;
  q.depth = 3;
  return q;
}

// A node: participant "talker" with one writer and one reader on kTopic.
struct Talker {
  Talker(Vendor vendor, int domain) {
    participant = createParticipant(vendor, {domain, "talker"});
    writer = participant->createWriter(kTopic, testType(), writerQos());
    reader = participant->createReader(kTopic, testType(), readerQos(), [](DataReader&) {});
  }
  std::unique_ptr<Participant> participant;
  std::unique_ptr<DataWriter> writer;
  std::unique_ptr<DataReader> reader;
};

const EndpointInfo* findEndpoint(const GraphSnapshot& snap, const Guid& guid) {
  for (const EndpointInfo& e : snap.endpoints)
    if (e.guid == guid) return &e;
  return nullptr;
}

// ---- Without DDS traffic ------------------------------------------------------------------

TEST(GraphHelpers, VendorFromGuidUsesTheRtpsVendorId) {
  Guid guid{};
  guid[0] = 0x01;
  guid[1] = 0x0f;
  EXPECT_EQ(vendorNameFromGuid(guid), "fastdds");
  guid[1] = 0x10;
  EXPECT_EQ(vendorNameFromGuid(guid), "cyclonedds");
  guid[1] = 0x01;
  EXPECT_EQ(vendorNameFromGuid(guid), "connext");
  guid[0] = 0xab;
  guid[1] = 0xcd;
  EXPECT_EQ(vendorNameFromGuid(guid), "vendor 0xabcd");
}

TEST(GraphHelpers, ParticipantInfoFromOurUserData) {
  Guid guid{};
  guid[0] = 0x01;
  guid[1] = 0x10;
  const ParticipantInfo info = detail::makeParticipantInfo(
      guid, "auv:node=planner;host=sub1;pid=42;vendor=fastdds", "dds_name");
  EXPECT_TRUE(info.is_auv);
  EXPECT_EQ(info.guid, guid);
  EXPECT_EQ(info.node_name, "planner");
  EXPECT_EQ(info.host, "sub1");
  EXPECT_EQ(info.pid, 42);
  EXPECT_EQ(info.vendor, "fastdds");  // USER_DATA wins over the GUID's vendor id

  // What participantUserData() produces parses back.
  const ParticipantInfo own =
      detail::makeParticipantInfo(guid, participantUserData(Vendor::CYCLONEDDS, "mapper"), "");
  EXPECT_TRUE(own.is_auv);
  EXPECT_EQ(own.node_name, "mapper");
  EXPECT_EQ(own.host, hostName());
  EXPECT_EQ(own.pid, getpid());
  EXPECT_EQ(own.vendor, "cyclonedds");
}

TEST(GraphHelpers, ParticipantInfoOfForeignParticipants) {
  Guid guid{};
  guid[0] = 0x01;
  guid[1] = 0x0f;
  const ParticipantInfo named = detail::makeParticipantInfo(guid, "", "ros2_node");
  EXPECT_FALSE(named.is_auv);
  EXPECT_EQ(named.node_name, "ros2_node");
  EXPECT_EQ(named.host, "");
  EXPECT_EQ(named.pid, 0);
  EXPECT_EQ(named.vendor, "fastdds");

  const ParticipantInfo other = detail::makeParticipantInfo(guid, "enclave=/;", "");
  EXPECT_FALSE(other.is_auv);
  EXPECT_EQ(other.node_name, "");

  const ParticipantInfo bad_pid =
      detail::makeParticipantInfo(guid, std::string("auv:node=x;pid=abc\0\0", 20), "");
  EXPECT_TRUE(bad_pid.is_auv);
  EXPECT_EQ(bad_pid.node_name, "x");
  EXPECT_EQ(bad_pid.pid, 0);
  EXPECT_EQ(bad_pid.vendor, "fastdds");
}

TEST(GraphHelpers, SnapshotQueries) {
  GraphSnapshot snap;
  ParticipantInfo p;
  p.guid[15] = 1;
  p.node_name = "n";
  snap.participants.push_back(p);
  EndpointInfo w;
  w.topic = "/a/b";
  w.type = "auv::msg::X";
  w.is_writer = true;
  w.guid[15] = 2;
  w.participant = p.guid;
  EndpointInfo r = w;
  r.is_writer = false;
  r.type = "auv::msg::Y";
  r.guid[15] = 3;
  EndpointInfo other = w;
  other.topic = "/c";
  other.guid[15] = 4;
  snap.endpoints = {w, r, other};

  const auto types = snap.topicTypes();
  ASSERT_EQ(types.size(), 2u);
  EXPECT_EQ(types.at("/a/b"), (std::set<std::string>{"auv::msg::X", "auv::msg::Y"}));
  EXPECT_EQ(types.at("/c"), (std::set<std::string>{"auv::msg::X"}));
  ASSERT_EQ(snap.endpointsOn("/a/b", true).size(), 1u);
  EXPECT_EQ(snap.endpointsOn("a/b", true)[0].guid, w.guid);
  ASSERT_EQ(snap.endpointsOn("a/b", false).size(), 1u);
  EXPECT_EQ(snap.endpointsOn("a/b", false)[0].guid, r.guid);
  EXPECT_TRUE(snap.hasTopic("c"));
  EXPECT_FALSE(snap.hasTopic("/a"));
  ASSERT_NE(snap.participant(p.guid), nullptr);
  EXPECT_EQ(snap.participant(p.guid)->node_name, "n");
  EXPECT_EQ(snap.participant(w.guid), nullptr);
}

TEST(GraphInspector, RejectsBadDomain) {
  EXPECT_THROW(GraphInspector(Vendor::CYCLONEDDS, -1), std::invalid_argument);
  EXPECT_THROW(GraphInspector(Vendor::FASTDDS, 233), std::invalid_argument);
}

// ---- Real discovery: every (talker vendor, inspector vendor) pair -------------------------

class GraphPairTest : public ::testing::TestWithParam<std::tuple<Vendor, Vendor, int>> {
 protected:
  Vendor talkerVendor() const { return std::get<0>(GetParam()); }
  Vendor inspectorVendor() const { return std::get<1>(GetParam()); }
  /// One domain per test and pair: `base` (a multiple of 10 per test) + the pair's index.
  int domain(int base) const { return base + std::get<2>(GetParam()); }
};

TEST_P(GraphPairTest, SeesNodeTopicAndQos) {
  Talker talker(talkerVendor(), domain(100));
  GraphInspector inspector(inspectorVendor(), domain(100));
  const Guid pguid = talker.participant->guid();
  const Guid wguid = talker.writer->guid();
  const Guid rguid = talker.reader->guid();
  const GraphSnapshot snap = inspector.waitFor(
      [&](const GraphSnapshot& s) {
        return s.participant(pguid) != nullptr && findEndpoint(s, wguid) != nullptr &&
               findEndpoint(s, rguid) != nullptr;
      },
      kDiscoveryTimeout);

  // The node, as USER_DATA announces it.
  ASSERT_EQ(snap.participants.size(), 1u) << "only the talker is on this domain";
  const ParticipantInfo* node = snap.participant(pguid);
  ASSERT_NE(node, nullptr) << "talker not discovered within " << kDiscoveryTimeout.count() << " ms";
  EXPECT_TRUE(node->is_auv);
  EXPECT_EQ(node->node_name, "talker");
  EXPECT_EQ(node->vendor, toString(talkerVendor()));
  EXPECT_EQ(vendorNameFromGuid(node->guid), toString(talkerVendor()));
  EXPECT_EQ(node->pid, getpid());
  EXPECT_EQ(node->host, hostName());

  // The topic and its type, ROS-style.
  EXPECT_EQ(snap.topicTypes(),
            (std::map<std::string, std::set<std::string>>{{kTopic, {testType().name}}}));

  // The writer and what it announced.
  const std::vector<EndpointInfo> writers = snap.endpointsOn(kTopic, true);
  ASSERT_EQ(writers.size(), 1u);
  const EndpointInfo& w = writers[0];
  EXPECT_EQ(w.guid, wguid);
  EXPECT_EQ(w.participant, pguid);
  EXPECT_TRUE(w.is_writer);
  EXPECT_EQ(w.topic, kTopic);
  EXPECT_EQ(w.type, testType().name);
  EXPECT_EQ(w.qos.name, "");
  EXPECT_EQ(w.qos.reliability, Reliability::RELIABLE);
  EXPECT_EQ(w.qos.durability, Durability::TRANSIENT_LOCAL);
  EXPECT_DOUBLE_EQ(w.qos.deadline_s, 2.0);
  EXPECT_EQ(w.qos.liveliness, Liveliness::AUTOMATIC);
  EXPECT_DOUBLE_EQ(w.qos.liveliness_lease_s, 0.0);
  // History and resource limits travel only from Cyclone endpoints to Cyclone inspectors.
  const bool history_on_wire =
      talkerVendor() == Vendor::CYCLONEDDS && inspectorVendor() == Vendor::CYCLONEDDS;
  EXPECT_EQ(w.history_known, history_on_wire);
  if (history_on_wire) {
    EXPECT_EQ(w.qos.history, History::KEEP_LAST);
    EXPECT_EQ(w.qos.depth, 7);
    EXPECT_EQ(w.qos.max_samples, 100);
    EXPECT_EQ(w.qos.max_instances, 10);
    EXPECT_EQ(w.qos.max_samples_per_instance, 10);
  } else {
    EXPECT_EQ(w.qos.depth, 1) << "the DDS default stands in for the unknown depth";
  }

  // The reader.
  const std::vector<EndpointInfo> readers = snap.endpointsOn(kTopic, false);
  ASSERT_EQ(readers.size(), 1u);
  const EndpointInfo& r = readers[0];
  EXPECT_EQ(r.guid, rguid);
  EXPECT_FALSE(r.is_writer);
  EXPECT_EQ(r.participant, pguid);
  EXPECT_EQ(r.qos.reliability, Reliability::BEST_EFFORT);
  EXPECT_EQ(r.qos.durability, Durability::VOLATILE);
  EXPECT_DOUBLE_EQ(r.qos.deadline_s, 0.0);
  EXPECT_EQ(r.history_known, history_on_wire);
  if (history_on_wire) EXPECT_EQ(r.qos.depth, 3);
}

TEST_P(GraphPairTest, ExcludesInspectors) {
  Talker talker(talkerVendor(), domain(110));
  GraphInspector inspector(inspectorVendor(), domain(110));
  GraphInspector other(talkerVendor(), domain(110));  // another `auv` CLI run, say
  const Guid pguid = talker.participant->guid();
  // Wait for the talker's endpoints: by then both inspectors have long been discovered.
  const GraphSnapshot snap = inspector.waitFor(
      [&](const GraphSnapshot& s) { return s.endpoints.size() >= 2; }, kDiscoveryTimeout);
  ASSERT_EQ(snap.endpoints.size(), 2u);
  ASSERT_EQ(snap.participants.size(), 1u);
  EXPECT_EQ(snap.participants[0].guid, pguid);
  EXPECT_EQ(snap.participant(inspector.guid()), nullptr);
  EXPECT_EQ(snap.participant(other.guid()), nullptr);
  for (const EndpointInfo& e : snap.endpoints) EXPECT_EQ(e.participant, pguid);

  // The inspector's own GUID is a real one of its vendor.
  EXPECT_EQ(vendorNameFromGuid(inspector.guid()), toString(inspectorVendor()));
  EXPECT_EQ(inspector.vendor(), inspectorVendor());
  EXPECT_EQ(inspector.domainId(), domain(110));
}

TEST_P(GraphPairTest, DeletedEndpointsAndParticipantsDisappear) {
  // Fast DDS 2.9.1 ignores the disposes Cyclone 0.10.2 sends when it deletes an endpoint or a
  // participant: a Fast DDS inspector drops a Cyclone participant (and its endpoints) only
  // when its lease expires. Cyclone's default lease is 10 s; make it 1 s for this pair.
  const bool lease_only =
      talkerVendor() == Vendor::CYCLONEDDS && inspectorVendor() == Vendor::FASTDDS;
  if (lease_only) {
    ASSERT_EQ(std::getenv("CYCLONEDDS_URI"), nullptr) << "the test sets its own";
    setenv("CYCLONEDDS_URI",
           "<CycloneDDS><Domain Id=\"any\"><General><Interfaces>"
           "<NetworkInterface name=\"lo\" multicast=\"true\"/></Interfaces>"
           "<AllowMulticast>true</AllowMulticast></General>"
           "<Discovery><LeaseDuration>1s</LeaseDuration></Discovery></Domain></CycloneDDS>",
           1);
  }
  auto talker = std::make_unique<Talker>(talkerVendor(), domain(120));
  if (lease_only) unsetenv("CYCLONEDDS_URI");
  GraphInspector inspector(inspectorVendor(), domain(120));
  const Guid pguid = talker->participant->guid();
  const Guid wguid = talker->writer->guid();
  GraphSnapshot snap = inspector.waitFor(
      [&](const GraphSnapshot& s) { return s.endpoints.size() == 2; }, kDiscoveryTimeout);
  ASSERT_EQ(snap.endpoints.size(), 2u);
  ASSERT_NE(snap.participant(pguid), nullptr);

  if (!lease_only) {
    // The writer goes alone; the reader and the node stay.
    talker->writer.reset();
    snap =
        inspector.waitFor([&](const GraphSnapshot& s) { return findEndpoint(s, wguid) == nullptr; },
                          kDiscoveryTimeout);
    EXPECT_EQ(findEndpoint(snap, wguid), nullptr) << "deleted writer still listed";
    EXPECT_EQ(snap.endpoints.size(), 1u);
    EXPECT_NE(snap.participant(pguid), nullptr);
  }

  const auto start = std::chrono::steady_clock::now();
  talker.reset();
  snap = inspector.waitFor(
      [&](const GraphSnapshot& s) { return s.participants.empty() && s.endpoints.empty(); },
      kDiscoveryTimeout);
  const auto took =
      std::chrono::duration_cast<milliseconds>(std::chrono::steady_clock::now() - start);
  EXPECT_TRUE(snap.participants.empty())
      << "deleted participant still listed after " << took.count() << " ms";
  EXPECT_TRUE(snap.endpoints.empty()) << "endpoints of a deleted participant still listed";
  if (!lease_only) EXPECT_LT(took.count(), 2000) << "removal should be announced, not timed out";
}

std::string pairName(const ::testing::TestParamInfo<GraphPairTest::ParamType>& info) {
  return toString(std::get<0>(info.param)) + "_talker_" + toString(std::get<1>(info.param)) +
         "_inspector";
}

// (talker, inspector, index): each test uses domain base + index (100-103, 110-113, 120-123).
INSTANTIATE_TEST_SUITE_P(Pairs, GraphPairTest,
                         ::testing::Values(std::make_tuple(Vendor::CYCLONEDDS, Vendor::CYCLONEDDS,
                                                           0),
                                           std::make_tuple(Vendor::CYCLONEDDS, Vendor::FASTDDS, 1),
                                           std::make_tuple(Vendor::FASTDDS, Vendor::CYCLONEDDS, 2),
                                           std::make_tuple(Vendor::FASTDDS, Vendor::FASTDDS, 3)),
                         pairName);

}  // namespace
}  // namespace auv::interfaces
