// The foxglove_bridge component on real DDS and real sockets (domain ids in test/README.md):
// topics of both vendors advertised with their OMG IDL and forwarded byte for byte, a DDS
// reader only while a client subscribes, topics that go unadvertised; the visual channels from
// odometry, map, tree, path and camera topics; malformed messages answered with a status; a
// slow client that loses best-effort samples without holding up the publisher or a fast
// client; the access token; mission/abort called through the bridge.
#include <gtest/gtest.h>

#include <cstring>

#include "auv/interfaces/msg_time.h"
#include "bridge_harness.h"
#include "serialized_test_util.h"
#include "ws_client.h"

namespace auv::foxglove_bridge {
namespace {

using namespace std::chrono_literals;
using interfaces::Vendor;
using nlohmann::json;
using test::BridgeHarness;
using test::WsClient;

// The payload of a Message Data frame and its subscription id.
std::vector<uint8_t> payloadOf(const std::vector<uint8_t>& frame,
                               uint32_t* subscription = nullptr) {
  if (subscription) std::memcpy(subscription, frame.data() + 1, 4);
  return std::vector<uint8_t>(frame.begin() + 13, frame.end());
}

std::vector<json> jsonFrames(const WsClient& client, uint32_t subscription) {
  std::vector<json> out;
  for (const auto& f : client.frames()) {
    uint32_t id = 0;
    const auto p = payloadOf(f, &id);
    if (f[0] == 1 && id == subscription) out.push_back(json::parse(p.begin(), p.end()));
  }
  return out;
}

TEST(FoxgloveBridge, ForwardsTopicsOfBothVendorsUnchanged) {
  const int domain = 128;
  BridgeHarness bridge(Vendor::CYCLONEDDS, domain);
  auto fast = interfaces::createParticipant(Vendor::FASTDDS, {domain, "fast"});
  auto cyclone = interfaces::createParticipant(Vendor::CYCLONEDDS, {domain, "cyclone"});
  const auto& odometry = interfaces::typeSupportByName("Odometry");
  const auto& text = interfaces::typeSupportByName("String");
  auto w1 = fast->createWriter("/t/fast", odometry, interfaces::stateQos());
  auto w2 = cyclone->createWriter("/t/cyclone", text, interfaces::commandQos());
  WsClient client(bridge.uri());
  ASSERT_TRUE(client.waitOpen(5s));
  ASSERT_TRUE(client.waitFor(
      [&] { return client.channel("/t/fast") >= 0 && client.channel("/t/cyclone") >= 0; }, 10s));
  for (const auto& m : client.texts("advertise"))
    for (const auto& c : m["channels"])
      if (c["topic"] == "/t/fast") {
        EXPECT_EQ(c["encoding"], "cdr");
        EXPECT_EQ(c["schemaEncoding"], "omgidl");
        EXPECT_EQ(c["schemaName"], "auv::msg::Odometry");
        EXPECT_EQ(c["schema"], odometry.omg_idl);
      }
  EXPECT_EQ(w1->matchedReaders(), 0);  // nobody subscribed: no DDS reader
  EXPECT_EQ(bridge.component().forwarder().activeReaders(), 0u);
  client.subscribe(1, client.channel("/t/fast"));
  client.subscribe(2, client.channel("/t/cyclone"));
  ASSERT_TRUE(
      client.waitFor([&] { return w1->matchedReaders() == 1 && w2->matchedReaders() == 1; }, 10s));
  auto o = std::static_pointer_cast<msg::Odometry>(odometry.create_sample());
  o->pose().pose().position().x(12.5);
  o->header().frame_id("world");
  auto s = std::static_pointer_cast<msg::String>(text.create_sample());
  s->data("hello");
  std::this_thread::sleep_for(200ms);
  w1->write(o.get());
  w2->write(s.get());
  ASSERT_TRUE(client.waitFor([&] { return client.frames().size() >= 2; }, 10s));
  for (const auto& f : client.frames()) {
    uint32_t id = 0;
    const auto payload = payloadOf(f, &id);
    if (id == 1)
      interfaces::test::expectWireBytes(payload, interfaces::test::cdrOf(odometry, o.get()),
                                        interfaces::test::alignmentGaps(odometry, o.get()));
    if (id == 2) interfaces::test::expectWireBytes(payload, interfaces::test::cdrOf(text, s.get()));
  }
  // Unsubscribed: the reader goes; the writer gone: the channel is unadvertised.
  client.sendText(R"({"op":"unsubscribe","subscriptionIds":[1]})");
  // (Read from the bridge: a Fast DDS writer does not see a Cyclone reader go until its
  // participant's lease ends, docs/architecture.md.)
  const auto& forwarder = bridge.component().forwarder();
  ASSERT_TRUE(client.waitFor([&] { return forwarder.activeReaders() == 1; }, 10s));
  w2.reset();
  EXPECT_TRUE(client.waitFor([&] { return client.channel("/t/cyclone") < 0; }, 10s));
  EXPECT_GE(client.channel("/t/fast"), 0);
}

TEST(FoxgloveBridge, DrawsMapPlannerVehicleAndCameras) {
  const int domain = 129;
  BridgeHarness bridge(Vendor::FASTDDS, domain, {"vehicle_period:=0.05", "map_period:=0.1"});
  interfaces::Node source("source", interfaces::nodeOptions(Vendor::CYCLONEDDS, domain));
  auto odometry = source.createPublisher<msg::Odometry>("nav/odometry", interfaces::stateQos());
  auto truth = source.createPublisher<msg::Odometry>("sim/ground_truth", interfaces::stateQos());
  auto map = source.createPublisher<msg::OctomapUpdate>("map/update", interfaces::mapQos());
  auto tree = source.createPublisher<msg::PlannerTree>("planner/tree", interfaces::viewingQos());
  auto camera = source.createPublisher<msg::CompressedImage>("camera/left/compressed",
                                                             interfaces::sensorDataQos());
  WsClient client(bridge.uri());
  ASSERT_TRUE(client.waitOpen(5s));
  ASSERT_TRUE(client.waitFor([&] { return client.channel("/foxglove/camera/left") >= 0; }, 10s));
  const char* topics[] = {"/tf", "/foxglove/vehicle", "/foxglove/map", "/foxglove/planner",
                          "/foxglove/camera/left"};
  for (uint32_t i = 0; i < 5; ++i) {
    ASSERT_GE(client.channel(topics[i]), 0) << topics[i];
    client.subscribe(10 + i, client.channel(topics[i]));
  }
  std::this_thread::sleep_for(500ms);
  // A 2-leaf map, as the mapping component sends it (FULL, .ot stream).
  octomap::OcTree octree(0.5);
  octree.updateNode(octomap::point3d(1, 1, 1), true);
  octree.updateNode(octomap::point3d(2, 1, 1), true);
  std::stringstream stream;
  octree.write(stream);
  const std::string bytes = stream.str();
  msg::OctomapUpdate update;
  update.map_id("octomap");
  update.sequence_number(1);
  update.kind(msg::OCTOMAP_UPDATE_FULL);
  update.encoding(msg::OCTOMAP_ENCODING_FULL);
  update.tree_type("OcTree");
  update.resolution(0.5);
  update.data(std::vector<uint8_t>(bytes.begin(), bytes.end()));
  map->publish(update);
  msg::PlannerTree t;
  t.nodes(std::vector<msg::Point>(2));
  t.parents({-1, 0});
  msg::CompressedImage image;
  image.format("jpeg");
  image.data({0xff, 0xd8, 0xff});
  for (int i = 0; i < 20; ++i) {
    msg::Odometry o;
    o.header().stamp(interfaces::toMsgTime(1000000000LL * (i + 1)));
    o.pose().pose().position().x(i);
    o.pose().pose().orientation().w(1);
    odometry->publish(o);
    o.pose().pose().position().y(0.1);
    truth->publish(o);
    tree->publish(t);
    camera->publish(image);
    std::this_thread::sleep_for(50ms);
  }
  ASSERT_TRUE(client.waitFor(
      [&] {
        for (uint32_t i = 0; i < 5; ++i)
          if (jsonFrames(client, 10 + i).empty()) return false;
        return true;
      },
      10s))
      << "tf " << jsonFrames(client, 10).size() << " vehicle " << jsonFrames(client, 11).size()
      << " map " << jsonFrames(client, 12).size() << " planner " << jsonFrames(client, 13).size()
      << " camera " << jsonFrames(client, 14).size();
  // /tf: the vehicle in world, and world (NED) under the z-up display frame map.
  ASSERT_TRUE(client.waitFor(
      [&] {
        bool vehicle = false, display = false;
        for (const json& tf : jsonFrames(client, 10)) {
          vehicle =
              vehicle || (tf["parent_frame_id"] == "world" && tf["child_frame_id"] == "vehicle" &&
                          tf["translation"]["x"].get<double>() > 0);
          display = display || (tf["parent_frame_id"] == "map" && tf["child_frame_id"] == "world");
        }
        return vehicle && display;
      },
      5s))
      << jsonFrames(client, 10).back().dump();
  ASSERT_TRUE(
      client.waitFor([&] { return jsonFrames(client, 11).back()["entities"].size() == 3; }, 5s));
  const json vehicle = jsonFrames(client, 11).back();
  EXPECT_EQ(vehicle["entities"][0]["id"], "vehicle");
  EXPECT_EQ(vehicle["entities"][1]["id"], "trajectory_estimated");
  EXPECT_EQ(vehicle["entities"][2]["id"], "trajectory_true");
  const json m = jsonFrames(client, 12).back();
  EXPECT_EQ(m["entities"][0]["id"], "map");
  EXPECT_EQ(m["entities"][0]["cubes"].size(), 2u);
  EXPECT_EQ(jsonFrames(client, 13).back()["entities"][0]["id"], "tree");
  EXPECT_EQ(jsonFrames(client, 14).back()["data"], "/9j/");
  EXPECT_EQ(jsonFrames(client, 14).back()["format"], "jpeg");
}

TEST(FoxgloveBridge, MalformedMessagesGetAStatusAndSlowClientsDropBestEffort) {
  const int domain = 2;
  BridgeHarness bridge(Vendor::CYCLONEDDS, domain, {"send_buffer_limit:=200000"});
  auto participant = interfaces::createParticipant(Vendor::FASTDDS, {domain, "camera"});
  const auto& type = interfaces::typeSupportByName("CompressedImage");
  auto writer =
      participant->createWriter("/camera/big/compressed", type, interfaces::sensorDataQos());
  WsClient slow(bridge.uri()), fast(bridge.uri());
  ASSERT_TRUE(slow.waitOpen(5s) && fast.waitOpen(5s));
  for (const std::string bad :
       {"nonsense", "{\"op\":\"subscribe\",\"subscriptions\":[{\"id\":\"x\"}]}",
        "{\"op\":\"unsubscribe\",\"subscriptionIds\":[77]}", "[]", "{\"op\":\"fetchAsset\"}"})
    fast.sendText(bad);
  fast.sendBinary({0x7f, 1, 2});
  fast.sendBinary({});
  ASSERT_TRUE(fast.waitFor([&] { return fast.texts("status").size() == 7; }, 5s))
      << fast.texts("status").size();
  for (const auto& s : fast.texts("status")) EXPECT_EQ(s["level"], 2) << s;
  ASSERT_TRUE(fast.waitFor([&] { return fast.channel("/camera/big/compressed") >= 0; }, 10s));
  const auto channel = static_cast<uint32_t>(fast.channel("/camera/big/compressed"));
  fast.subscribe(1, channel);
  slow.subscribe(1, channel);
  ASSERT_TRUE(fast.waitFor([&] { return writer->matchedReaders() == 1; }, 10s));
  std::this_thread::sleep_for(300ms);
  slow.setDelay(200ms);
  auto image = std::static_pointer_cast<msg::CompressedImage>(type.create_sample());
  image->data(std::vector<uint8_t>(100000, 7));
  double slowest_write = 0;
  const int samples = 60;
  for (int i = 0; i < samples; ++i) {
    const auto start = std::chrono::steady_clock::now();
    writer->write(image.get());
    slowest_write =
        std::max(slowest_write,
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    std::this_thread::sleep_for(20ms);
  }
  fast.waitFor([&] { return fast.frames().size() >= samples; }, 5s);
  EXPECT_GE(fast.frames().size(), samples * 9 / 10);  // loopback best effort: a few may go
  EXPECT_GT(bridge.component().server().droppedMessages(), 0u);
  EXPECT_LT(slowest_write, 0.1);  // the publisher never waits for the bridge's clients
  EXPECT_LT(slow.frames().size(), fast.frames().size());
  // Still serving after all that: a new client connects and is advertised the topic.
  WsClient late(bridge.uri());
  ASSERT_TRUE(late.waitOpen(5s));
  EXPECT_TRUE(late.waitFor([&] { return late.channel("/camera/big/compressed") >= 0; }, 5s));
}

TEST(FoxgloveBridge, TokenAndServices) {
  const int domain = 1;
  BridgeHarness bridge(Vendor::FASTDDS, domain,
                       {"token:=s3cret", "services:=true", "parameters:=true"});
  WsClient none(bridge.uri()), wrong(bridge.uri("?token=nope")),
      bare(bridge.uri("?token=s3cret"), "");
  EXPECT_FALSE(none.waitOpen(5s));
  EXPECT_EQ(none.httpStatus(), 401);
  EXPECT_FALSE(wrong.waitOpen(5s));
  EXPECT_FALSE(bare.waitOpen(5s));  // no subprotocol
  EXPECT_EQ(bare.httpStatus(), 400);
  interfaces::Node mission("mission", interfaces::nodeOptions(Vendor::CYCLONEDDS, domain));
  int aborts = 0;
  auto service = mission.createService<msg::TriggerRequest, msg::TriggerReply>(
      "mission/abort", [&](const msg::TriggerRequest&, msg::TriggerReply& reply) {
        ++aborts;
        reply.message("aborted");
      });
  interfaces::Executor executor;
  executor.add(mission);
  std::thread spin([&] { executor.spin(); });
  struct Stop {  // also when an assertion returns early
    interfaces::Executor& e;
    std::thread& t;
    interfaces::Node& n;
    ~Stop() {
      e.shutdown();
      t.join();
      e.remove(n);
    }
  } stop{executor, spin, mission};
  WsClient client(bridge.uri("?token=s3cret"));
  ASSERT_TRUE(client.waitOpen(5s));
  ASSERT_TRUE(client.waitFor([&] { return !client.texts("advertiseServices").empty(); }, 5s));
  EXPECT_EQ(client.texts("serverInfo").at(0)["capabilities"],
            json::array({"services", "parameters"}));
  uint32_t abort_id = 0;
  const json services = client.texts("advertiseServices")[0]["services"];
  for (const auto& s : services)
    if (s["name"] == "mission/abort") abort_id = s["id"];
  ASSERT_NE(abort_id, 0u) << services.dump();
  std::vector<uint8_t> call = {2, 0, 0, 0, 0, 5, 0, 0, 0, 4, 0, 0, 0, 'j', 's', 'o', 'n', '{', '}'};
  call[1] = static_cast<uint8_t>(abort_id);
  client.sendBinary(call);
  ASSERT_TRUE(client.waitFor([&] { return !client.frames().empty(); }, 15s));
  const auto frame = client.frames().front();
  ASSERT_EQ(frame[0], 3);
  const std::string reply(frame.begin() + 17, frame.end());
  EXPECT_EQ(json::parse(reply)["message"], "aborted") << reply;
  EXPECT_EQ(aborts, 1);
  client.sendText(R"({"op":"getParameters","parameterNames":["port"],"id":"p"})");
  ASSERT_TRUE(client.waitFor([&] { return !client.texts("parameterValues").empty(); }, 5s));
  EXPECT_EQ(client.texts("parameterValues")[0]["parameters"][0]["value"], 0);
}

}  // namespace
}  // namespace auv::foxglove_bridge
