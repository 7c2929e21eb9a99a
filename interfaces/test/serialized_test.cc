// Serialized (type-erased) endpoints on real DDS: for every vendor pairing, a typed writer's
// samples reach a serialized reader as their CDR bytes, a serialized writer's bytes reach
// typed readers, a reliable stream arrives whole and in order, malformed bytes are dropped
// by typed readers and kept by serialized ones, and a late serialized reader with the QoS
// learnt from the graph gets a keyed transient-local history; every type survives being
// recorded as bytes and replayed. Each test runs the pairings in
// turn on its own domain (51-56, 58; test/README.md), on topics named after the pairing.
// What is byte-identical and what is not: docs/architecture.md, "Serialized endpoints".
#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <cstring>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "auv/interfaces/executor.h"
#include "auv/interfaces/graph.h"
#include "auv/interfaces/node.h"
#include "auv/interfaces/serialized.h"
#include "sample_filler.h"
#include "serialized_test_util.h"

namespace auv::interfaces {
namespace {

using namespace std::chrono_literals;
using test::cdrOf;
using test::Collector;
using test::kPairs;
using test::pairName;
using test::VendorPair;

int64_t nowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// Publishes until the collector has `count` samples (volatile readers miss what was written
// before they matched).
template <class Publish>
bool publishUntil(Collector& collector, size_t count, Publish publish) {
  const auto deadline = std::chrono::steady_clock::now() + 15s;
  while (std::chrono::steady_clock::now() < deadline) {
    publish();
    if (collector.waitFor(count, 50ms)) return true;
  }
  return false;
}

msg::Odometry someOdometry() {
  msg::Odometry odom;
  msg::fromYaml(YAML::Load("{header: {stamp: {sec: 12, nanosec: 345}, frame_id: world},"
                           " child_frame_id: base_link, altitude: 3.25, source_flags: 5,"
                           " pose: {pose: {position: {x: 1.5, y: -2, z: 30.125},"
                           " orientation: {w: 1}}}, twist: {twist: {linear: {x: 0.7}}}}"),
                odom, "");
  odom.pose().covariance()[7] = -0.5;
  return odom;
}

TEST(SerializedTest, TypedSamplesArriveAsTheirCdrBytes) {
  const int domain = 51;
  for (const VendorPair& pair : kPairs) {
    SCOPED_TRACE(pairName(pair));
    const std::string prefix = "/serialized/" + pairName(pair);
    Node talker("talker", nodeOptions(pair.writer, domain));
    auto recorder = createParticipant(pair.reader, {domain, "recorder"});

    // An odd-sized String, an Odometry, a keyed OctomapUpdate; ROS-style names on the typed
    // side, DDS names on the serialized side.
    const msg::TypeSupport& string_type = typeSupportByName("String");
    Collector strings, odometries, maps;
    auto string_reader = recorder->createSerializedReader(prefix.substr(1) + "/text", string_type,
                                                          commandQos(), strings.callback());
    auto odom_reader =
        recorder->createSerializedReader(prefix + "/odom", typeSupportByName("auv::msg::Odometry"),
                                         commandQos(), odometries.callback());
    auto map_reader = recorder->createSerializedReader(
        prefix + "/map", typeSupportByName("auv/msg/OctomapUpdate"), mapQos(), maps.callback());

    auto string_pub = talker.createPublisher<msg::String>(prefix + "/text", commandQos());
    auto odom_pub = talker.createPublisher<msg::Odometry>(prefix + "/odom", commandQos());
    auto map_pub = talker.createPublisher<msg::OctomapUpdate>(prefix + "/map", mapQos());
    msg::String text;
    text.data("hello");  // 4 + 4 + 6 bytes: not a multiple of 4
    const msg::Odometry odom = someOdometry();
    msg::OctomapUpdate map;
    map.map_id("octomap");
    map.sequence_number(3);
    map.data(std::vector<uint8_t>(100001, 0x5a));
    map_pub->publish(map);  // once: transient local

    const int64_t before = nowNs();
    ASSERT_TRUE(publishUntil(strings, 1, [&] { string_pub->publish(text); }));
    ASSERT_TRUE(publishUntil(odometries, 1, [&] { odom_pub->publish(odom); }));
    ASSERT_TRUE(maps.waitFor(1, 15s));

    // A Fast DDS writer may leave stale bytes in alignment gaps (test::expectWireBytes).
    const bool fast = pair.writer == Vendor::FASTDDS;
    const SerializedSample s = strings.samples().front();
    test::expectWireBytes(s.cdr, cdrOf(string_type, &text));
    EXPECT_EQ(test::decode<msg::String>(string_type, s.cdr).data(), "hello");
    EXPECT_EQ(s.publication, string_pub->guid());
    EXPECT_GE(s.source_timestamp_ns, before - 1000000000);
    EXPECT_GE(s.reception_timestamp_ns, s.source_timestamp_ns - 1000000000);  // one host
    EXPECT_LE(s.reception_timestamp_ns, nowNs());
    if (s.sequence_number != -1) EXPECT_GE(s.sequence_number, 1);

    const msg::TypeSupport& odom_type = typeSupportByName("Odometry");
    const SerializedSample o = odometries.samples().front();
    test::expectWireBytes(o.cdr, cdrOf(odom_type, &odom),
                          fast ? test::alignmentGaps(odom_type, &odom) : std::vector<bool>{});
    EXPECT_EQ(YAML::Dump(msg::toYaml(test::decode<msg::Odometry>(odom_type, o.cdr))),
              YAML::Dump(msg::toYaml(odom)));

    const msg::TypeSupport& map_type = typeSupportByName("OctomapUpdate");
    const SerializedSample m = maps.samples().front();
    test::expectWireBytes(m.cdr, cdrOf(map_type, &map),
                          fast ? test::alignmentGaps(map_type, &map) : std::vector<bool>{});
    EXPECT_EQ(test::decode<msg::OctomapUpdate>(map_type, m.cdr).data(), map.data());
    EXPECT_EQ(m.publication, map_pub->guid());
  }
}

msg::MissionStatus missionStatus(const std::string& id, int update) {
  msg::MissionStatus status;
  status.mission_id(id);
  status.message(id + " update " + std::to_string(update));
  return status;
}

TEST(SerializedTest, SerializedWriterBytesArriveAtTypedSubscriptions) {
  const int domain = 52;
  const msg::TypeSupport& string_type = typeSupportByName("String");
  const msg::TypeSupport& status_type = typeSupportByName("MissionStatus");
  for (const VendorPair& pair : kPairs) {
    SCOPED_TRACE(pairName(pair));
    const std::string prefix = "/serialized/" + pairName(pair);
    auto player = createParticipant(pair.writer, {domain, "player"});
    Node listener("listener", nodeOptions(pair.reader, domain));
    Executor executor;
    executor.add(listener);
    std::vector<std::string> texts;
    std::map<std::string, std::string> statuses;
    auto text_sub = listener.createSubscription<msg::String>(
        prefix + "/text", commandQos(),
        std::function<void(const msg::String&)>(
            [&](const msg::String& m) { texts.push_back(m.data()); }));
    auto status_sub = listener.createSubscription<msg::MissionStatus>(
        prefix + "/status", latchedStateQos(),
        std::function<void(const msg::MissionStatus&)>(
            [&](const msg::MissionStatus& m) { statuses[m.mission_id()] = m.message(); }));

    auto text_writer = player->createSerializedWriter(prefix + "/text", string_type, commandQos());
    auto status_writer =
        player->createSerializedWriter(prefix + "/status", status_type, latchedStateQos());
    // Keyed and transient local: the last sample of each instance reaches the reader.
    for (int update = 1; update <= 2; ++update) {
      for (const char* id : {"alpha", "bravo"}) {
        const msg::MissionStatus status = missionStatus(id, update);
        status_writer->write(cdrOf(status_type, &status));
      }
    }
    // What a recorder received over the network, alignment padding included, replays as is.
    msg::String text;
    text.data("hello");
    std::vector<uint8_t> padded = cdrOf(string_type, &text);
    padded.resize(16, 0);
    const auto deadline = std::chrono::steady_clock::now() + 15s;
    while (texts.empty() && std::chrono::steady_clock::now() < deadline) {
      text_writer->write(padded);
      executor.spinUntil([&] { return !texts.empty(); }, 50ms);
    }
    ASSERT_FALSE(texts.empty());
    EXPECT_EQ(texts.front(), "hello");
    ASSERT_TRUE(executor.spinUntil([&] { return statuses.size() == 2; }, 15s));
    EXPECT_EQ(statuses["alpha"], "alpha update 2");
    EXPECT_EQ(statuses["bravo"], "bravo update 2");
    EXPECT_TRUE(executor.spinUntil([&] { return text_writer->matchedReaders() == 1; }, 5s));
  }
}

// Waits until the writer and the reader see each other (volatile: a sample written before
// would be missed).
template <class Writer, class Reader>
bool waitMatched(Writer& writer, Reader& reader) {
  const auto deadline = std::chrono::steady_clock::now() + 15s;
  while (std::chrono::steady_clock::now() < deadline) {
    if (writer.matchedReaders() >= 1 && reader.matchedWriters() >= 1) return true;
    std::this_thread::sleep_for(10ms);
  }
  return false;
}

void expectCompleteStream(Collector& collector, int count, const msg::TypeSupport& type) {
  ASSERT_TRUE(collector.waitFor(count, 30s)) << collector.size() << " of " << count;
  const std::vector<SerializedSample> samples = collector.samples();
  ASSERT_EQ(samples.size(), static_cast<size_t>(count));
  for (int i = 0; i < count; ++i) {
    msg::String expected;
    expected.data("sample " + std::to_string(i));
    test::expectWireBytes(samples[i].cdr, cdrOf(type, &expected));
    // Sequence numbers, when the vendor gives them, count every sample: no gap.
    if (i > 0 && samples[i].sequence_number >= 0 && samples[i - 1].sequence_number >= 0)
      EXPECT_EQ(samples[i].sequence_number, samples[i - 1].sequence_number + 1) << i;
  }
}

TEST(SerializedTest, ReliableStreamArrivesComplete) {
  const int domain = 53;
  const int count = 2000;
  const msg::TypeSupport& string_type = typeSupportByName("String");
  for (const VendorPair& pair : kPairs) {
    SCOPED_TRACE(pairName(pair));
    const std::string prefix = "/serialized/" + pairName(pair);
    Node talker("talker", nodeOptions(pair.writer, domain));
    auto player = createParticipant(pair.writer, {domain, "player"});
    auto recorder = createParticipant(pair.reader, {domain, "recorder"});
    Collector typed_stream, serialized_stream;
    auto typed_reader = recorder->createSerializedReader(
        prefix + "/typed", string_type, bulkTransferQos(), typed_stream.callback());
    auto serialized_reader = recorder->createSerializedReader(
        prefix + "/serialized", string_type, bulkTransferQos(), serialized_stream.callback());
    auto pub = talker.createPublisher<msg::String>(prefix + "/typed", bulkTransferQos());
    auto writer =
        player->createSerializedWriter(prefix + "/serialized", string_type, bulkTransferQos());
    struct Matched {
      Publisher<msg::String>& pub;
      int matchedReaders() const { return pub.matchedSubscriptions(); }
    } typed{*pub};
    ASSERT_TRUE(waitMatched(typed, *typed_reader));
    ASSERT_TRUE(waitMatched(*writer, *serialized_reader));
    for (int i = 0; i < count; ++i) {
      msg::String text;
      text.data("sample " + std::to_string(i));
      pub->publish(text);
      writer->write(cdrOf(string_type, &text));
    }
    expectCompleteStream(typed_stream, count, string_type);
    expectCompleteStream(serialized_stream, count, string_type);
  }
}

TEST(SerializedTest, MalformedBytesAreDroppedByTypedReadersAndKeptBySerializedOnes) {
  const int domain = 54;
  const msg::TypeSupport& string_type = typeSupportByName("String");
  const std::vector<std::vector<uint8_t>> malformed = {
      {0, 1, 0, 0},                               // a header and nothing else
      {0, 1, 0, 0, 0xe8, 0x03, 0, 0, 'a', 'b'},   // 1000 characters announced, 2 there
      {0, 1, 0, 0, 0x00, 0xff, 0xff, 0x7f, 'x'},  // ~2 GB announced
      {0, 0, 0, 0, 0x01, 0x02, 0x03},             // big endian, truncated length
  };
  for (const VendorPair& pair : kPairs) {
    SCOPED_TRACE(pairName(pair));
    const std::string topic = "/serialized/" + pairName(pair) + "/text";
    auto player = createParticipant(pair.writer, {domain, "player"});
    auto recorder = createParticipant(pair.reader, {domain, "recorder"});
    Node listener("listener", nodeOptions(pair.reader, domain));
    Executor executor;
    executor.add(listener);
    std::vector<std::string> texts;
    auto sub = listener.createSubscription<msg::String>(
        topic, commandQos(), std::function<void(const msg::String&)>([&](const msg::String& m) {
          texts.push_back(m.data());
        }));
    Collector recorded;
    auto reader =
        recorder->createSerializedReader(topic, string_type, commandQos(), recorded.callback());
    auto writer = player->createSerializedWriter(topic, string_type, commandQos());
    msg::String ok;
    ok.data("ok");
    const std::vector<uint8_t> valid = cdrOf(string_type, &ok);
    // The recorder keeps what it was sent, decodable or not.
    const auto kept_truncated = [&] {
      for (const SerializedSample& s : recorded.samples()) {
        if (s.cdr.size() >= malformed[1].size() &&
            std::equal(malformed[1].begin(), malformed[1].end(), s.cdr.begin()))
          return true;
      }
      return false;
    };
    // Rounds until both readers matched and had one (volatile: either may match late).
    const auto deadline = std::chrono::steady_clock::now() + 15s;
    while ((texts.empty() || !kept_truncated()) && std::chrono::steady_clock::now() < deadline) {
      for (const auto& bytes : malformed) writer->write(bytes);
      writer->write(valid);
      executor.spinUntil([&] { return !texts.empty(); }, 50ms);
    }
    ASSERT_FALSE(texts.empty()) << "the valid sample behind the malformed ones never arrived";
    EXPECT_TRUE(kept_truncated());
    executor.spinUntil([] { return false; }, 200ms);
    for (const std::string& text : texts) EXPECT_EQ(text, "ok");
  }
}

TEST(SerializedTest, LateReaderWithQosFromTheGraphGetsKeyedHistory) {
  const int domain = 55;
  const msg::TypeSupport& status_type = typeSupportByName("MissionStatus");
  const msg::TypeSupport& path_type = typeSupportByName("Path");
  for (const VendorPair& pair : kPairs) {
    SCOPED_TRACE(pairName(pair));
    const std::string prefix = "/serialized/" + pairName(pair);
    Node mission("mission", nodeOptions(pair.writer, domain));
    auto status_pub =
        mission.createPublisher<msg::MissionStatus>(prefix + "/status", latchedStateQos());
    auto path_pub = mission.createPublisher<msg::Path>(prefix + "/path", viewingQos());
    for (int update = 1; update <= 3; ++update)
      for (const char* id : {"alpha", "bravo"}) status_pub->publish(missionStatus(id, update));

    // A recorder joining later learns the writers' QoS from discovery.
    GraphInspector graph(pair.reader, domain);
    const GraphSnapshot snap = graph.waitFor(
        [&](const GraphSnapshot& s) {
          return !s.endpointsOn(prefix + "/status", true).empty() &&
                 !s.endpointsOn(prefix + "/path", true).empty();
        },
        10s);
    const QosProfile status_qos = compatibleReaderQos(snap.endpointsOn(prefix + "/status", true));
    const QosProfile path_qos = compatibleReaderQos(snap.endpointsOn(prefix + "/path", true));
    EXPECT_EQ(status_qos.reliability, Reliability::RELIABLE);
    EXPECT_EQ(status_qos.durability, Durability::TRANSIENT_LOCAL);
    EXPECT_EQ(path_qos.reliability, Reliability::BEST_EFFORT);
    EXPECT_EQ(path_qos.durability, Durability::VOLATILE);
    EXPECT_NO_THROW(status_qos.check());

    auto recorder = createParticipant(pair.reader, {domain, "recorder"});
    Collector statuses, paths;
    auto status_reader = recorder->createSerializedReader(prefix + "/status", status_type,
                                                          status_qos, statuses.callback());
    auto path_reader =
        recorder->createSerializedReader(prefix + "/path", path_type, path_qos, paths.callback());
    ASSERT_TRUE(statuses.waitFor(2, 15s));
    std::map<std::string, std::string> last;
    for (const SerializedSample& s : statuses.samples()) {
      const auto status = test::decode<msg::MissionStatus>(status_type, s.cdr);
      last[status.mission_id()] = status.message();
    }
    EXPECT_EQ(last["alpha"], "alpha update 3");
    EXPECT_EQ(last["bravo"], "bravo update 3");
    msg::Path path;
    path.query_id(7);
    ASSERT_TRUE(publishUntil(paths, 1, [&] { path_pub->publish(path); }));
    EXPECT_EQ(test::decode<msg::Path>(path_type, paths.samples().front().cdr).query_id(), 7u);
  }
}

TEST(SerializedTest, ParticipantKeepsTypedAndSerializedUsesOfATypeApart) {
  const int domain = 56;
  const msg::TypeSupport& string_type = typeSupportByName("String");
  const msg::TypeSupport& status_type = typeSupportByName("MissionStatus");
  for (Vendor vendor : {Vendor::CYCLONEDDS, Vendor::FASTDDS}) {
    SCOPED_TRACE(toString(vendor));
    auto participant = createParticipant(vendor, {domain, "mixed"});
    auto typed = participant->createWriter("mixed/typed", string_type, commandQos());
    EXPECT_THROW(
        participant->createSerializedReader("mixed/serialized", string_type, commandQos(), nullptr),
        std::runtime_error);
    auto writer = participant->createSerializedWriter("mixed/status", status_type, commandQos());
    EXPECT_THROW(participant->createReader("mixed/status", status_type, commandQos(), nullptr),
                 std::runtime_error);
    // Bytes that are not XCDR1, and a keyed sample whose key cannot be read.
    EXPECT_THROW(writer->write(std::vector<uint8_t>{0, 7, 0, 0, 1, 0, 0, 0}),
                 std::invalid_argument);
    EXPECT_THROW(writer->write(std::vector<uint8_t>{0, 1}), std::invalid_argument);
    EXPECT_THROW(writer->write(std::vector<uint8_t>{0, 1, 0, 0, 0xff, 0xff, 0xff, 0x7f}),
                 std::invalid_argument);
    const msg::MissionStatus status = missionStatus("alpha", 1);
    EXPECT_NO_THROW(writer->write(cdrOf(status_type, &status)));
  }
  EXPECT_THROW(typeSupportByName("NoSuchType"), std::invalid_argument);
}

// What `auv bag record` then `play` does, for every type: a typed writer's samples, taken
// as bytes by a serialized reader, written again by a serialized writer, reach a typed reader
// (of the first vendor again) with every value intact.
TEST(SerializedTest, EveryTypeRecordedAndReplayedArrivesUnchanged) {
  const int domain = 58;
  for (const VendorPair& pair : kPairs) {
    SCOPED_TRACE(pairName(pair));
    const std::string prefix = "replay/" + pairName(pair) + "/";
    auto source = createParticipant(pair.writer, {domain, "source"});
    auto recorder = createParticipant(pair.reader, {domain, "recorder"});  // reads and replays
    auto sink = createParticipant(pair.writer, {domain, "sink"});
    struct Case {
      const msg::TypeSupport* type;
      std::shared_ptr<void> sample;
      std::unique_ptr<DataWriter> writer;
      std::unique_ptr<Collector> recorded;
      std::unique_ptr<SerializedReader> reader;
      std::unique_ptr<SerializedWriter> player;
      std::unique_ptr<DataReader> replayed;
    };
    std::vector<Case> cases;
    for (const msg::TypeSupport& type : msg::allTypes()) {
      const std::string name = type.name.substr(type.name.rfind(':') + 1);
      Case c{&type, test::SampleFiller(type).sample(), nullptr, std::make_unique<Collector>()};
      // Transient local, keep last 1: written once, each sample reaches its reader.
      c.writer = source->createWriter(prefix + "in/" + name, type, latchedStateQos());
      c.writer->write(c.sample.get());
      c.reader = recorder->createSerializedReader(prefix + "in/" + name, type, latchedStateQos(),
                                                  c.recorded->callback());
      c.player = recorder->createSerializedWriter(prefix + "out/" + name, type, latchedStateQos());
      c.replayed = sink->createReader(prefix + "out/" + name, type, latchedStateQos(), nullptr);
      cases.push_back(std::move(c));
    }
    for (Case& c : cases) {
      ASSERT_TRUE(c.recorded->waitFor(1, 20s)) << c.type->name;
      c.player->write(c.recorded->samples().front().cdr);
    }
    for (Case& c : cases) {
      SCOPED_TRACE(c.type->name);
      auto replayed = c.type->create_sample();
      SampleInfo info;
      const auto deadline = std::chrono::steady_clock::now() + 20s;
      bool taken = false;
      while (!(taken = c.replayed->take(replayed.get(), &info)) &&
             std::chrono::steady_clock::now() < deadline)
        std::this_thread::sleep_for(10ms);
      ASSERT_TRUE(taken);
      EXPECT_EQ(YAML::Dump(c.type->to_yaml(replayed.get())),
                YAML::Dump(c.type->to_yaml(c.sample.get())));
      EXPECT_EQ(info.publication, c.player->guid());
    }
  }
}

EndpointInfo writerWith(Reliability reliability, Durability durability, int depth, bool known) {
  EndpointInfo e;
  e.is_writer = true;
  e.qos.reliability = reliability;
  e.qos.durability = durability;
  e.qos.depth = depth;
  e.qos.deadline_s = 0.5;
  e.history_known = known;
  return e;
}

TEST(CompatibleReaderQosTest, TheWeakestOfferDecides) {
  const auto reliable_latched =
      writerWith(Reliability::RELIABLE, Durability::TRANSIENT_LOCAL, 500, true);
  const auto best_effort = writerWith(Reliability::BEST_EFFORT, Durability::VOLATILE, 5, false);
  QosProfile qos = compatibleReaderQos({reliable_latched});
  EXPECT_EQ(qos.reliability, Reliability::RELIABLE);
  EXPECT_EQ(qos.durability, Durability::TRANSIENT_LOCAL);
  EXPECT_EQ(qos.depth, 500);  // a deeper writer history than the default arrives whole
  EXPECT_EQ(qos.deadline_s, 0);
  EXPECT_EQ(qos.liveliness_lease_s, 0);
  EXPECT_EQ(qos.name, "compatible");
  qos = compatibleReaderQos({reliable_latched, best_effort}, 10);
  EXPECT_EQ(qos.reliability, Reliability::BEST_EFFORT);
  EXPECT_EQ(qos.durability, Durability::VOLATILE);
  EXPECT_EQ(qos.depth, 500);
  qos = compatibleReaderQos({});
  EXPECT_EQ(qos.reliability, Reliability::BEST_EFFORT);
  EXPECT_EQ(qos.durability, Durability::VOLATILE);
  EXPECT_EQ(qos.depth, 100);
  for (const QosProfile& q : {compatibleReaderQos({reliable_latched}), compatibleReaderQos({})})
    EXPECT_NO_THROW(q.check());
}

}  // namespace
}  // namespace auv::interfaces
