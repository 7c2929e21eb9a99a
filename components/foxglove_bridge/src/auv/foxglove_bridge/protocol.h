#pragma once
// The Foxglove WebSocket protocol v1 (subprotocol `foxglove.websocket.v1`, public spec:
// github.com/foxglove/ws-protocol, docs/spec.md): the server's messages built as text (JSON)
// or binary frames, and the client's messages parsed into structs. No sockets, no DDS: the
// bridge's core (bridge_core.h) and the tests use it. A message that does not follow the spec
// throws ProtocolError naming the field ("subscribe: subscriptions[1].channelId: expected an
// unsigned 32-bit integer, got \"x\"").

#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

namespace auv::foxglove_bridge {

constexpr const char* kSubprotocol = "foxglove.websocket.v1";

/// A client message that breaks the spec: what and where, for a status message.
class ProtocolError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class StatusLevel { INFO = 0, WARNING = 1, ERROR = 2 };

/// A server channel as advertised.
struct Channel {
  uint32_t id = 0;
  std::string topic;
  std::string encoding;         ///< "cdr" (DDS topics), "json" (visual topics)
  std::string schema_name;      ///< "auv::msg::Odometry", "foxglove.SceneUpdate"
  std::string schema;           ///< OMG IDL text, or a JSON schema
  std::string schema_encoding;  ///< "omgidl", "jsonschema"
};

/// A service as advertised (requests and responses in `encoding`).
struct ServiceDescription {
  uint32_t id = 0;
  std::string name;  ///< "mission/start"
  std::string type;  ///< "auv::msg::StartMissionRequest"
  std::string encoding = "json";
  std::string request_schema_name, request_schema;
  std::string response_schema_name, response_schema;
  std::string schema_encoding = "jsonschema";
};

// ---- server -> client, text ----

std::string serverInfoMessage(const std::string& name, const std::vector<std::string>& capabilities,
                              const std::vector<std::string>& supported_encodings,
                              const std::string& session_id,
                              const std::map<std::string, std::string>& metadata);
std::string statusMessage(StatusLevel level, const std::string& message);
std::string advertiseMessage(const std::vector<Channel>& channels);
std::string unadvertiseMessage(const std::vector<uint32_t>& channel_ids);
std::string advertiseServicesMessage(const std::vector<ServiceDescription>& services);
std::string serviceCallFailureMessage(uint32_t service_id, uint32_t call_id,
                                      const std::string& message);
/// `parameters`: a JSON array of {name, value[, type]}; `id` empty: left out.
std::string parameterValuesMessage(const nlohmann::json& parameters, const std::string& id);

// ---- server -> client, binary ----

enum BinaryOpcode : uint8_t {
  MESSAGE_DATA = 0x01,           ///< server: subscription id, timestamp, payload
  TIME = 0x02,                   ///< server: timestamp
  SERVICE_CALL_RESPONSE = 0x03,  ///< server: service id, call id, encoding, payload
  CLIENT_MESSAGE_DATA = 0x01,    ///< client: channel id, payload
  SERVICE_CALL_REQUEST = 0x02,   ///< client: service id, call id, encoding, payload
};

/// Message Data: opcode, subscription id (u32), receive time (u64 ns), payload; little endian.
std::vector<uint8_t> messageDataFrame(uint32_t subscription_id, uint64_t timestamp_ns,
                                      const uint8_t* payload, size_t size);
std::vector<uint8_t> serviceCallResponseFrame(uint32_t service_id, uint32_t call_id,
                                              const std::string& encoding,
                                              const std::string& payload);

// ---- client -> server ----

struct Subscribe {
  struct Entry {
    uint32_t id = 0;
    uint32_t channel_id = 0;
  };
  std::vector<Entry> subscriptions;
};
struct Unsubscribe {
  std::vector<uint32_t> subscription_ids;
};
struct GetParameters {
  std::vector<std::string> names;  ///< empty: all
  std::string id;
};
struct SetParameters {
  std::vector<std::pair<std::string, nlohmann::json>> parameters;  ///< name, value
  std::string id;
};
struct ServiceCallRequest {
  uint32_t service_id = 0;
  uint32_t call_id = 0;
  std::string encoding;
  std::string payload;
};
/// A message of the spec this server does not offer (clientPublish, connection graph,
/// parameter subscriptions, assets): answered with a status, not an error of the client.
struct Unsupported {
  std::string op;
};
using ClientMessage = std::variant<Subscribe, Unsubscribe, GetParameters, SetParameters,
                                   ServiceCallRequest, Unsupported>;

/// Parses a client text message; throws ProtocolError naming the field.
ClientMessage parseTextMessage(const std::string& text);
/// Parses a client binary message; throws ProtocolError.
ClientMessage parseBinaryMessage(const uint8_t* data, size_t size);

}  // namespace auv::foxglove_bridge
