#include "auv/foxglove_bridge/protocol.h"

#include <cstring>
#include <limits>

namespace auv::foxglove_bridge {
namespace {

using nlohmann::json;

// Short text of a JSON value for an error ("got ..."), at most 40 characters.
std::string shown(const json& value) {
  std::string text = value.dump();
  if (text.size() > 40) text = text.substr(0, 37) + "...";
  return text;
}

const json& field(const json& object, const std::string& op, const std::string& name) {
  const auto it = object.find(name);
  if (it == object.end()) throw ProtocolError(op + ": missing field '" + name + "'");
  return *it;
}

uint32_t asUint32(const json& value, const std::string& where) {
  // Integers only: 1.5 or "1" are refused, as is anything beyond 32 bits.
  if (value.is_number_unsigned() && value.get<uint64_t>() <= std::numeric_limits<uint32_t>::max())
    return static_cast<uint32_t>(value.get<uint64_t>());
  if (value.is_number_integer() && value.get<int64_t>() >= 0 &&
      value.get<int64_t>() <= std::numeric_limits<uint32_t>::max())
    return static_cast<uint32_t>(value.get<int64_t>());
  throw ProtocolError(where + ": expected an unsigned 32-bit integer, got " + shown(value));
}

const json& asArray(const json& value, const std::string& where) {
  if (!value.is_array()) throw ProtocolError(where + ": expected an array, got " + shown(value));
  return value;
}

std::string asString(const json& value, const std::string& where) {
  if (!value.is_string()) throw ProtocolError(where + ": expected a string, got " + shown(value));
  return value.get<std::string>();
}

std::string optionalId(const json& object, const std::string& op) {
  const auto it = object.find("id");
  if (it == object.end() || it->is_null()) return "";
  return asString(*it, op + ": id");
}

Subscribe parseSubscribe(const json& m) {
  Subscribe s;
  const json& list = asArray(field(m, "subscribe", "subscriptions"), "subscribe: subscriptions");
  for (size_t i = 0; i < list.size(); ++i) {
    const std::string where = "subscribe: subscriptions[" + std::to_string(i) + "]";
    if (!list[i].is_object()) throw ProtocolError(where + ": expected an object");
    s.subscriptions.push_back({asUint32(field(list[i], where, "id"), where + ".id"),
                               asUint32(field(list[i], where, "channelId"), where + ".channelId")});
  }
  return s;
}

Unsubscribe parseUnsubscribe(const json& m) {
  Unsubscribe u;
  const json& list =
      asArray(field(m, "unsubscribe", "subscriptionIds"), "unsubscribe: subscriptionIds");
  for (size_t i = 0; i < list.size(); ++i)
    u.subscription_ids.push_back(
        asUint32(list[i], "unsubscribe: subscriptionIds[" + std::to_string(i) + "]"));
  return u;
}

GetParameters parseGetParameters(const json& m) {
  GetParameters g;
  const json& list =
      asArray(field(m, "getParameters", "parameterNames"), "getParameters: parameterNames");
  for (size_t i = 0; i < list.size(); ++i)
    g.names.push_back(
        asString(list[i], "getParameters: parameterNames[" + std::to_string(i) + "]"));
  g.id = optionalId(m, "getParameters");
  return g;
}

SetParameters parseSetParameters(const json& m) {
  SetParameters s;
  const json& list = asArray(field(m, "setParameters", "parameters"), "setParameters: parameters");
  for (size_t i = 0; i < list.size(); ++i) {
    const std::string where = "setParameters: parameters[" + std::to_string(i) + "]";
    if (!list[i].is_object()) throw ProtocolError(where + ": expected an object");
    const auto value = list[i].find("value");
    s.parameters.emplace_back(asString(field(list[i], where, "name"), where + ".name"),
                              value == list[i].end() ? json() : *value);
  }
  s.id = optionalId(m, "setParameters");
  return s;
}

uint32_t readU32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) | static_cast<uint32_t>(p[1]) << 8 |
         static_cast<uint32_t>(p[2]) << 16 | static_cast<uint32_t>(p[3]) << 24;
}

void putU32(std::vector<uint8_t>& out, size_t at, uint32_t v) {
  for (int i = 0; i < 4; ++i) out[at + i] = static_cast<uint8_t>(v >> (8 * i));
}

}  // namespace

std::string serverInfoMessage(const std::string& name, const std::vector<std::string>& capabilities,
                              const std::vector<std::string>& supported_encodings,
                              const std::string& session_id,
                              const std::map<std::string, std::string>& metadata) {
  json m = {{"op", "serverInfo"},
            {"name", name},
            {"capabilities", capabilities},
            {"metadata", metadata},
            {"sessionId", session_id}};
  if (!supported_encodings.empty()) m["supportedEncodings"] = supported_encodings;
  return m.dump();
}

std::string statusMessage(StatusLevel level, const std::string& message) {
  // dump with replacement: a message quoting a client's invalid UTF-8 must still be JSON.
  return json{{"op", "status"}, {"level", static_cast<int>(level)}, {"message", message}}.dump(
      -1, ' ', false, json::error_handler_t::replace);
}

std::string advertiseMessage(const std::vector<Channel>& channels) {
  json list = json::array();
  for (const Channel& c : channels) {
    list.push_back({{"id", c.id},
                    {"topic", c.topic},
                    {"encoding", c.encoding},
                    {"schemaName", c.schema_name},
                    {"schema", c.schema},
                    {"schemaEncoding", c.schema_encoding}});
  }
  return json{{"op", "advertise"}, {"channels", list}}.dump();
}

std::string unadvertiseMessage(const std::vector<uint32_t>& channel_ids) {
  return json{{"op", "unadvertise"}, {"channelIds", channel_ids}}.dump();
}

std::string advertiseServicesMessage(const std::vector<ServiceDescription>& services) {
  json list = json::array();
  for (const ServiceDescription& s : services) {
    list.push_back({{"id", s.id},
                    {"name", s.name},
                    {"type", s.type},
                    {"request",
                     {{"encoding", s.encoding},
                      {"schemaName", s.request_schema_name},
                      {"schemaEncoding", s.schema_encoding},
                      {"schema", s.request_schema}}},
                    {"response",
                     {{"encoding", s.encoding},
                      {"schemaName", s.response_schema_name},
                      {"schemaEncoding", s.schema_encoding},
                      {"schema", s.response_schema}}}});
  }
  return json{{"op", "advertiseServices"}, {"services", list}}.dump();
}

std::string serviceCallFailureMessage(uint32_t service_id, uint32_t call_id,
                                      const std::string& message) {
  return json{{"op", "serviceCallFailure"},
              {"serviceId", service_id},
              {"callId", call_id},
              {"message", message}}
      .dump(-1, ' ', false, json::error_handler_t::replace);
}

std::string parameterValuesMessage(const json& parameters, const std::string& id) {
  json m = {{"op", "parameterValues"}, {"parameters", parameters}};
  if (!id.empty()) m["id"] = id;
  return m.dump(-1, ' ', false, json::error_handler_t::replace);
}

std::vector<uint8_t> messageDataFrame(uint32_t subscription_id, uint64_t timestamp_ns,
                                      const uint8_t* payload, size_t size) {
  std::vector<uint8_t> frame(13 + size);
  frame[0] = MESSAGE_DATA;
  putU32(frame, 1, subscription_id);
  for (int i = 0; i < 8; ++i) frame[5 + i] = static_cast<uint8_t>(timestamp_ns >> (8 * i));
  if (size > 0) std::memcpy(frame.data() + 13, payload, size);
  return frame;
}

std::vector<uint8_t> serviceCallResponseFrame(uint32_t service_id, uint32_t call_id,
                                              const std::string& encoding,
                                              const std::string& payload) {
  std::vector<uint8_t> frame(13 + encoding.size() + payload.size());
  frame[0] = SERVICE_CALL_RESPONSE;
  putU32(frame, 1, service_id);
  putU32(frame, 5, call_id);
  putU32(frame, 9, static_cast<uint32_t>(encoding.size()));
  std::memcpy(frame.data() + 13, encoding.data(), encoding.size());
  if (!payload.empty())
    std::memcpy(frame.data() + 13 + encoding.size(), payload.data(), payload.size());
  return frame;
}

ClientMessage parseTextMessage(const std::string& text) {
  json m;
  try {
    m = json::parse(text);
  } catch (const json::exception& e) {
    throw ProtocolError(std::string("not JSON: ") + e.what());
  }
  if (!m.is_object()) throw ProtocolError("expected a JSON object with 'op', got " + shown(m));
  const std::string op = asString(field(m, "message", "op"), "op");
  if (op == "subscribe") return parseSubscribe(m);
  if (op == "unsubscribe") return parseUnsubscribe(m);
  if (op == "getParameters") return parseGetParameters(m);
  if (op == "setParameters") return parseSetParameters(m);
  if (op == "advertise" || op == "unadvertise" || op == "subscribeParameterUpdates" ||
      op == "unsubscribeParameterUpdates" || op == "subscribeConnectionGraph" ||
      op == "unsubscribeConnectionGraph" || op == "fetchAsset")
    return Unsupported{op};
  throw ProtocolError("op: unknown operation " + shown(m["op"]));
}

ClientMessage parseBinaryMessage(const uint8_t* data, size_t size) {
  if (size == 0) throw ProtocolError("binary message: empty (no opcode)");
  if (data[0] == CLIENT_MESSAGE_DATA) return Unsupported{"client message data"};
  if (data[0] != SERVICE_CALL_REQUEST)
    throw ProtocolError("binary message: unknown opcode " + std::to_string(data[0]));
  if (size < 13)
    throw ProtocolError("service call request: " + std::to_string(size) +
                        " bytes, shorter than its 13-byte header");
  ServiceCallRequest r;
  r.service_id = readU32(data + 1);
  r.call_id = readU32(data + 5);
  const uint32_t encoding_length = readU32(data + 9);
  if (encoding_length > size - 13)
    throw ProtocolError("service call request: encoding length " + std::to_string(encoding_length) +
                        " runs past the message (" + std::to_string(size - 13) + " bytes left)");
  r.encoding.assign(reinterpret_cast<const char*>(data + 13), encoding_length);
  r.payload.assign(reinterpret_cast<const char*>(data + 13 + encoding_length),
                   size - 13 - encoding_length);
  return r;
}

}  // namespace auv::foxglove_bridge
