// The protocol messages against the spec (github.com/foxglove/ws-protocol, docs/spec.md):
// server messages' fields and byte layouts, client messages parsed, and every malformed
// message refused with a ProtocolError naming the field.
#include <gtest/gtest.h>

#include "auv/foxglove_bridge/protocol.h"

namespace auv::foxglove_bridge {
namespace {

using nlohmann::json;

TEST(Protocol, ServerMessagesHaveTheSpecsFields) {
  const json info = json::parse(serverInfoMessage("b", {"services"}, {"json"}, "42", {{"k", "v"}}));
  EXPECT_EQ(info["op"], "serverInfo");
  EXPECT_EQ(info["capabilities"], json::array({"services"}));
  EXPECT_EQ(info["supportedEncodings"], json::array({"json"}));
  EXPECT_EQ(info["sessionId"], "42");
  EXPECT_EQ(info["metadata"]["k"], "v");
  EXPECT_FALSE(json::parse(serverInfoMessage("b", {}, {}, "1", {})).contains("supportedEncodings"));
  const json status = json::parse(statusMessage(StatusLevel::ERROR, "bad \xff byte"));
  EXPECT_EQ(status["op"], "status");
  EXPECT_EQ(status["level"], 2);
  const json ad =
      json::parse(advertiseMessage({{7, "/a", "cdr", "auv::msg::X", "struct X {};", "omgidl"}}));
  EXPECT_EQ(ad["channels"][0]["id"], 7);
  EXPECT_EQ(ad["channels"][0]["schemaEncoding"], "omgidl");
  EXPECT_EQ(json::parse(unadvertiseMessage({1, 2}))["channelIds"], json::array({1, 2}));
  const json failure = json::parse(serviceCallFailureMessage(3, 4, "no"));
  EXPECT_EQ(failure["op"], "serviceCallFailure");
  EXPECT_EQ(failure["callId"], 4);
  ServiceDescription s;
  s.id = 1;
  s.name = "mission/abort";
  const json services = json::parse(advertiseServicesMessage({s}));
  EXPECT_EQ(services["services"][0]["request"]["encoding"], "json");
}

TEST(Protocol, BinaryFramesAreLittleEndian) {
  const uint8_t payload[] = {9, 8};
  const auto frame = messageDataFrame(0x01020304, 0x1122334455667788ULL, payload, 2);
  const std::vector<uint8_t> expected = {1,    4,    3,    2,    1,    0x88, 0x77, 0x66,
                                         0x55, 0x44, 0x33, 0x22, 0x11, 9,    8};
  EXPECT_EQ(frame, expected);
  const auto response = serviceCallResponseFrame(5, 6, "json", "{}");
  const std::vector<uint8_t> expected_response = {3, 5, 0, 0,   0,   6,   0,   0,   0,  4,
                                                  0, 0, 0, 'j', 's', 'o', 'n', '{', '}'};
  EXPECT_EQ(response, expected_response);
}

TEST(Protocol, ClientMessagesParse) {
  const auto s = std::get<Subscribe>(parseTextMessage(
      R"({"op":"subscribe","subscriptions":[{"id":0,"channelId":3},{"id":4294967295,"channelId":5}]})"));
  ASSERT_EQ(s.subscriptions.size(), 2u);
  EXPECT_EQ(s.subscriptions[1].id, 4294967295u);
  EXPECT_EQ(s.subscriptions[1].channel_id, 5u);
  const auto u =
      std::get<Unsubscribe>(parseTextMessage(R"({"op":"unsubscribe","subscriptionIds":[0,1]})"));
  EXPECT_EQ(u.subscription_ids, (std::vector<uint32_t>{0, 1}));
  const auto g = std::get<GetParameters>(
      parseTextMessage(R"({"op":"getParameters","parameterNames":["port"],"id":"r1"})"));
  EXPECT_EQ(g.names, std::vector<std::string>{"port"});
  EXPECT_EQ(g.id, "r1");
  const auto p = std::get<SetParameters>(
      parseTextMessage(R"({"op":"setParameters","parameters":[{"name":"a","value":2}]})"));
  EXPECT_EQ(p.parameters.at(0).second, 2);
  EXPECT_TRUE(std::holds_alternative<Unsupported>(parseTextMessage(R"({"op":"fetchAsset"})")));
  const std::vector<uint8_t> call = {2, 1, 0, 0,   0,   9,   0,   0,   0,  4,
                                     0, 0, 0, 'j', 's', 'o', 'n', '{', '}'};
  const auto r = std::get<ServiceCallRequest>(parseBinaryMessage(call.data(), call.size()));
  EXPECT_EQ(r.service_id, 1u);
  EXPECT_EQ(r.call_id, 9u);
  EXPECT_EQ(r.encoding, "json");
  EXPECT_EQ(r.payload, "{}");
}

// Each malformed message and a part of the error that names what is wrong.
TEST(Protocol, MalformedMessagesNameTheField) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"", "not JSON"},
      {"{\"op\":", "not JSON"},
      {"[1,2]", "expected a JSON object"},
      {"{}", "missing field 'op'"},
      {R"({"op":5})", "op: expected a string"},
      {R"({"op":"dance"})", "unknown operation \"dance\""},
      {R"({"op":"subscribe"})", "subscribe: missing field 'subscriptions'"},
      {R"({"op":"subscribe","subscriptions":{}})", "subscriptions: expected an array"},
      {R"({"op":"subscribe","subscriptions":[7]})", "subscriptions[0]: expected an object"},
      {R"({"op":"subscribe","subscriptions":[{"id":1}]})", "missing field 'channelId'"},
      {R"({"op":"subscribe","subscriptions":[{"id":-1,"channelId":1}]})",
       "subscriptions[0].id: expected an unsigned 32-bit integer, got -1"},
      {R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":1.5}]})", "channelId"},
      {R"({"op":"subscribe","subscriptions":[{"id":4294967296,"channelId":1}]})", "32-bit"},
      {R"({"op":"subscribe","subscriptions":[{"id":"1","channelId":1}]})", "got \"1\""},
      {R"({"op":"unsubscribe","subscriptionIds":[null]})", "subscriptionIds[0]"},
      {R"({"op":"getParameters","parameterNames":[1]})", "parameterNames[0]: expected a string"},
      {R"({"op":"getParameters","parameterNames":[],"id":3})", "getParameters: id"},
      {R"({"op":"setParameters","parameters":[{"value":1}]})", "missing field 'name'"},
  };
  for (const auto& [text, expected] : cases) {
    SCOPED_TRACE(text);
    try {
      parseTextMessage(text);
      ADD_FAILURE() << "accepted";
    } catch (const ProtocolError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  }
  const std::vector<std::vector<uint8_t>> binary = {
      {}, {9}, {2, 1, 0}, {2, 1, 0, 0, 0, 1, 0, 0, 0, 200, 0, 0, 0, 'j'}};
  for (const auto& bytes : binary) {
    EXPECT_THROW(parseBinaryMessage(bytes.data(), bytes.size()), ProtocolError);
  }
}

}  // namespace
}  // namespace auv::foxglove_bridge
