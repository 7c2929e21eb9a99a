// BridgeCore without sockets or DDS: what a client sees on connection, subscriptions and the
// listener's first/last-subscriber calls, samples to subscribers only, and every refused
// request answered with a status (level error) while the core keeps serving.
#include <gtest/gtest.h>

#include "auv/foxglove_bridge/bridge_core.h"

namespace auv::foxglove_bridge {
namespace {

using nlohmann::json;

struct Recorded : Transport, Listener {
  std::vector<std::pair<ClientId, json>> texts;
  std::vector<std::pair<ClientId, std::vector<uint8_t>>> frames;
  std::vector<std::string> events;
  void sendText(ClientId c, const std::string& t) override {
    texts.emplace_back(c, json::parse(t));
  }
  void sendBinary(ClientId c, std::vector<uint8_t> f, bool) override { frames.emplace_back(c, f); }
  void channelSubscribed(uint32_t ch) override { events.push_back("+" + std::to_string(ch)); }
  void channelUnsubscribed(uint32_t ch) override { events.push_back("-" + std::to_string(ch)); }
  void callService(ClientId, const ServiceCallRequest& r) override {
    events.push_back("call " + std::to_string(r.service_id));
  }
  json getParameters(const std::vector<std::string>&) override {
    return json::array({{{"name", "port"}, {"value", 8765}}});
  }
  void setParameters(const SetParameters&) override { throw std::invalid_argument("read-only"); }
  std::vector<json> of(ClientId c, const std::string& op) {
    std::vector<json> out;
    for (const auto& [client, m] : texts)
      if (client == c && m["op"] == op) out.push_back(m);
    return out;
  }
};

TEST(Core, ConnectSubscribePublishUnsubscribe) {
  Recorded r;
  BridgeCore core({}, r, r);
  const uint32_t a = core.addChannel({0, "/a", "cdr", "auv::msg::String", "idl", "omgidl"});
  core.clientConnected(1);
  ASSERT_GE(r.texts.size(), 2u);
  EXPECT_EQ(r.texts[0].second["op"], "serverInfo");
  EXPECT_EQ(r.texts[1].second["channels"][0]["topic"], "/a");
  const uint32_t b = core.addChannel({0, "/b", "json", "foxglove.SceneUpdate", "{}", "jsonschema"});
  EXPECT_EQ(r.of(1, "advertise").size(), 2u);  // the new channel goes to connected clients
  const uint8_t bytes[] = {0, 1, 0, 0, 42};
  EXPECT_FALSE(core.publish(a, 5, bytes, 5, false));
  core.textMessage(
      1, json{{"op", "subscribe"}, {"subscriptions", {{{"id", 10}, {"channelId", a}}}}}.dump());
  core.clientConnected(2);
  core.textMessage(
      2, json{{"op", "subscribe"}, {"subscriptions", {{{"id", 3}, {"channelId", a}}}}}.dump());
  EXPECT_EQ(r.events, std::vector<std::string>{"+" + std::to_string(a)});  // first only
  EXPECT_TRUE(core.publish(a, 5, bytes, 5, false));
  ASSERT_EQ(r.frames.size(), 2u);
  EXPECT_EQ(r.frames[0].second, (messageDataFrame(10, 5, bytes, 5)));
  EXPECT_EQ(r.frames[1].second, (messageDataFrame(3, 5, bytes, 5)));
  core.textMessage(1, R"({"op":"unsubscribe","subscriptionIds":[10]})");
  core.clientDisconnected(2);
  EXPECT_EQ(r.events.back(), "-" + std::to_string(a));
  EXPECT_FALSE(core.hasSubscribers(a));
  // A removed channel is unadvertised and its subscribers let go.
  core.textMessage(
      1, json{{"op", "subscribe"}, {"subscriptions", {{{"id", 11}, {"channelId", b}}}}}.dump());
  core.removeChannel(b);
  EXPECT_EQ(r.of(1, "unadvertise").back()["channelIds"], json::array({b}));
  EXPECT_EQ(r.events.back(), "-" + std::to_string(b));
  EXPECT_EQ(core.protocolErrors(), 0u);
}

TEST(Core, RefusedRequestsGetAnErrorStatus) {
  Recorded r;
  BridgeCore core({}, r, r);
  const uint32_t a = core.addChannel({0, "/a", "cdr", "X", "idl", "omgidl"});
  core.clientConnected(1);
  const std::vector<std::string> bad = {
      "garbage",
      json{{"op", "subscribe"}, {"subscriptions", {{{"id", 1}, {"channelId", 99}}}}}.dump(),
      R"({"op":"unsubscribe","subscriptionIds":[5]})",
      R"({"op":"getParameters","parameterNames":[]})", R"({"op":"advertise","channels":[]})"};
  for (const auto& text : bad) core.textMessage(1, text);
  core.textMessage(
      1, json{{"op", "subscribe"}, {"subscriptions", {{{"id", 1}, {"channelId", a}}}}}.dump());
  core.textMessage(
      1, json{{"op", "subscribe"}, {"subscriptions", {{{"id", 1}, {"channelId", a}}}}}.dump());
  core.textMessage(
      1, json{{"op", "subscribe"}, {"subscriptions", {{{"id", 2}, {"channelId", a}}}}}.dump());
  const std::vector<uint8_t> call = {2, 1, 0, 0, 0, 9, 0, 0, 0, 0, 0, 0, 0};
  core.binaryMessage(1, call.data(), call.size());  // services off
  const auto statuses = r.of(1, "status");
  ASSERT_EQ(statuses.size(), 8u);
  for (const auto& s : statuses) EXPECT_EQ(s["level"], 2) << s;
  EXPECT_NE(statuses[1]["message"].get<std::string>().find("no channel 99"), std::string::npos);
  EXPECT_NE(statuses[3]["message"].get<std::string>().find("not offered"), std::string::npos);
  EXPECT_NE(statuses[5]["message"].get<std::string>().find("already in use"), std::string::npos);
  EXPECT_NE(statuses[6]["message"].get<std::string>().find("already subscribed"),
            std::string::npos);
  EXPECT_EQ(core.protocolErrors(), 8u);
  EXPECT_TRUE(core.hasSubscribers(a));  // still serving
}

TEST(Core, ServicesAndParametersOnlyWhenEnabled) {
  Recorded r;
  CoreOptions options;
  options.services = true;
  options.parameters = true;
  BridgeCore core(options, r, r);
  ServiceDescription s;
  s.id = 1;
  s.name = "mission/abort";
  core.setServices({s});
  core.clientConnected(1);
  EXPECT_EQ(r.texts[0].second["capabilities"], json::array({"services", "parameters"}));
  EXPECT_EQ(r.of(1, "advertiseServices").size(), 1u);
  const std::vector<uint8_t> call = {2, 1, 0, 0, 0, 9, 0, 0, 0, 4, 0, 0, 0, 'j', 's', 'o', 'n'};
  core.binaryMessage(1, call.data(), call.size());
  EXPECT_EQ(r.events.back(), "call 1");
  std::vector<uint8_t> unknown = call;
  unknown[1] = 7;
  core.binaryMessage(1, unknown.data(), unknown.size());
  EXPECT_EQ(r.of(1, "serviceCallFailure").size(), 1u);
  core.textMessage(1, R"({"op":"getParameters","parameterNames":[],"id":"q"})");
  const auto values = r.of(1, "parameterValues");
  ASSERT_EQ(values.size(), 1u);
  EXPECT_EQ(values[0]["id"], "q");
  EXPECT_EQ(values[0]["parameters"][0]["value"], 8765);
  core.textMessage(1, R"({"op":"setParameters","parameters":[{"name":"port","value":1}]})");
  EXPECT_NE(r.of(1, "status").back()["message"].get<std::string>().find("read-only"),
            std::string::npos);
}

}  // namespace
}  // namespace auv::foxglove_bridge
