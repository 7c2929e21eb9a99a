#pragma once
// The bridge's WebSocket server on websocketpp (Debian's libwebsocketpp-dev, standalone asio):
// accepts clients that ask for the `foxglove.websocket.v1` subprotocol (and carry the access
// token when one is set), hands their messages to a BridgeCore and sends what the core asks
// for. One asio thread does all socket work; sendText/sendBinary only queue (websocketpp's
// send is thread-safe and does not wait for the socket), so a DDS callback never waits for a
// client. Each client has a send buffer limit: a best-effort sample that would take its
// queued bytes over the limit is dropped (counted); anything else is queued up to
// kReliableLimitFactor times the limit, beyond which the client is disconnected (it cannot
// keep up; Foxglove reconnects and gets the current state again).

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "auv/foxglove_bridge/bridge_core.h"

namespace auv::foxglove_bridge {

struct ServerOptions {
  std::string address = "127.0.0.1";
  uint16_t port = 8765;                         ///< 0: any free port (see port())
  size_t send_buffer_limit = 10 * 1000 * 1000;  ///< bytes queued per client
  /// Required as the `token` query parameter of the URL (ws://host:port/?token=...) when
  /// not empty; a client without it is refused with HTTP 401 before the WebSocket opens.
  std::string token;
  size_t max_client_message = 1 << 20;  ///< bytes; a larger client message closes it
};

/// Queued bytes beyond which even reliable data disconnects a client: factor x the limit.
constexpr size_t kReliableLimitFactor = 4;

class WebSocketServer : public Transport {
 public:
  /// Throws std::runtime_error naming the address and port when it cannot listen there.
  explicit WebSocketServer(ServerOptions options);
  ~WebSocketServer() override;
  WebSocketServer(const WebSocketServer&) = delete;
  WebSocketServer& operator=(const WebSocketServer&) = delete;

  /// Starts serving `core` on the asio thread.
  void start(BridgeCore& core);
  /// Closes every connection and stops the thread (also done by the destructor).
  void stop();
  /// The port listened on (the real one when the options said 0).
  uint16_t port() const { return port_; }

  void sendText(ClientId client, const std::string& text) override;
  void sendBinary(ClientId client, std::vector<uint8_t> frame, bool droppable) override;

  /// Best-effort samples dropped for slow clients, all clients together.
  uint64_t droppedMessages() const { return dropped_; }
  /// Clients disconnected for exceeding kReliableLimitFactor x the limit.
  uint64_t overflowDisconnects() const { return overflow_disconnects_; }
  /// Connections refused (no subprotocol, bad token).
  uint64_t refusedConnections() const { return refused_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  ServerOptions options_;
  uint16_t port_ = 0;
  std::atomic<uint64_t> dropped_{0};
  std::atomic<uint64_t> overflow_disconnects_{0};
  std::atomic<uint64_t> refused_{0};
};

/// True when `resource` ("/path?a=b&token=..."), has the query parameter token=`token`
/// (compared in constant time); %-escapes are decoded.
bool resourceHasToken(const std::string& resource, const std::string& token);

}  // namespace auv::foxglove_bridge
