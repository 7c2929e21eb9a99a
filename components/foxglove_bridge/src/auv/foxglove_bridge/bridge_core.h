#pragma once
// The bridge's protocol state, without sockets or DDS: the channels advertised, each client's
// subscriptions, and what a client message does. The WebSocket server (websocket_server.h)
// feeds it connections and messages and sends what it asks for through a Transport; the
// component (components/foxglove_bridge_component.h) adds and removes channels as topics come
// and go, starts a DDS reader when a channel gets its first subscriber (a Listener) and
// publishes samples with publish(). Thread-safe: every call may come from any thread; nothing
// is called back while the core's lock is held.

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "auv/foxglove_bridge/protocol.h"

namespace auv::foxglove_bridge {

using ClientId = uint64_t;

/// Where the core's messages go (the WebSocket server; a recorder in tests). Must not block.
class Transport {
 public:
  virtual ~Transport() = default;
  virtual void sendText(ClientId client, const std::string& text) = 0;
  /// `droppable`: a sample of a best-effort topic, which a slow client may lose.
  virtual void sendBinary(ClientId client, std::vector<uint8_t> frame, bool droppable) = 0;
};

/// What the component does for the core. Called without the core's lock held.
class Listener {
 public:
  virtual ~Listener() = default;
  /// `channel` got its first subscriber: start reading its topic.
  virtual void channelSubscribed(uint32_t channel) = 0;
  /// `channel` lost its last subscriber (or was removed): stop reading.
  virtual void channelUnsubscribed(uint32_t channel) = 0;
  /// A client called an advertised service; answer with core.serviceResponse/serviceFailure.
  virtual void callService(ClientId client, const ServiceCallRequest& request) = 0;
  /// getParameters: a JSON array of {name, value}; names empty: all.
  virtual nlohmann::json getParameters(const std::vector<std::string>& names) = 0;
  /// setParameters: sets each, throws std::invalid_argument naming the first refused.
  virtual void setParameters(const SetParameters& request) = 0;
};

struct CoreOptions {
  std::string name = "auv-inspect foxglove_bridge";
  bool services = false;    ///< advertise services and accept calls
  bool parameters = false;  ///< accept getParameters / setParameters
  std::map<std::string, std::string> metadata;
};

class BridgeCore {
 public:
  BridgeCore(CoreOptions options, Transport& transport, Listener& listener);

  // ---- channels (the component) ----
  /// Advertises a channel to every client; returns its id (fresh, from 1; `channel.id`
  /// ignored).
  uint32_t addChannel(Channel channel);
  /// Unadvertises it; its subscriptions end (channelUnsubscribed if it had any).
  void removeChannel(uint32_t channel_id);
  std::vector<Channel> channels() const;
  /// Advertised on connection when CoreOptions::services is set (ids given by the caller).
  void setServices(std::vector<ServiceDescription> services);

  /// Sends `payload` to every subscriber of `channel`; false when it has none.
  bool publish(uint32_t channel_id, uint64_t timestamp_ns, const uint8_t* payload, size_t size,
               bool droppable);
  bool hasSubscribers(uint32_t channel_id) const;

  // ---- clients (the server) ----
  void clientConnected(ClientId client);
  void clientDisconnected(ClientId client);
  /// Handles one message; a malformed or refused one is answered with a status (level error).
  void textMessage(ClientId client, const std::string& text);
  void binaryMessage(ClientId client, const uint8_t* data, size_t size);
  /// Sends a status message to one client.
  void sendStatus(ClientId client, StatusLevel level, const std::string& message);

  // ---- service answers (the component, any thread) ----
  void serviceResponse(ClientId client, const ServiceCallRequest& request,
                       const std::string& payload);
  void serviceFailure(ClientId client, const ServiceCallRequest& request,
                      const std::string& message);

  size_t clientCount() const;
  /// Client messages answered with an error status since start.
  uint64_t protocolErrors() const { return protocol_errors_; }

 private:
  struct Client {
    std::map<uint32_t, uint32_t> subscriptions;  // subscription id -> channel id
  };
  void handle(ClientId client, const ClientMessage& message);
  void subscribe(ClientId client, const Subscribe& request);
  void unsubscribe(ClientId client, const Unsubscribe& request);
  void parameters(ClientId client, const ClientMessage& message);
  void serviceCall(ClientId client, const ServiceCallRequest& request);
  // Subscribers of a channel, under the lock.
  size_t subscribersLocked(uint32_t channel_id) const;

  const CoreOptions options_;
  Transport& transport_;
  Listener& listener_;
  mutable std::mutex mutex_;
  std::map<uint32_t, Channel> channels_;
  std::vector<ServiceDescription> services_;
  std::map<ClientId, Client> clients_;
  // channel id -> (client, subscription id): who gets each sample.
  std::map<uint32_t, std::map<ClientId, uint32_t>> subscribers_;
  uint32_t next_channel_ = 1;
  std::atomic<uint64_t> protocol_errors_{0};
};

}  // namespace auv::foxglove_bridge
