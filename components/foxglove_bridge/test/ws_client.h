#pragma once
// A Foxglove protocol client for the C++ tests and the benchmark, on websocketpp's client
// (no hand-rolled framing): collects text messages as JSON and binary frames, and can be made
// slow (each message handler sleeps) to stand for a client that does not keep up.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace auv::foxglove_bridge::test {

class WsClient {
 public:
  /// Connects to `uri` with the foxglove.websocket.v1 subprotocol (or `subprotocol`).
  explicit WsClient(const std::string& uri,
                    const std::string& subprotocol = "foxglove.websocket.v1");
  ~WsClient();
  bool waitOpen(std::chrono::milliseconds timeout);
  /// True when the server refused or closed the connection.
  bool failed() const { return failed_ || closed_; }
  int httpStatus() const { return http_status_; }
  void sendText(const std::string& text);
  void sendBinary(const std::vector<uint8_t>& bytes);
  /// Sleeps this long in every message handler (a slow reader).
  void setDelay(std::chrono::milliseconds delay) { delay_ = delay.count(); }

  /// Waits until `pred` holds over the texts and frames received.
  bool waitFor(const std::function<bool()>& pred, std::chrono::milliseconds timeout);
  std::vector<nlohmann::json> texts(const std::string& op = "") const;
  std::vector<std::vector<uint8_t>> frames() const;
  /// Receive time (steady clock ns) of each frame, in order.
  std::vector<int64_t> frameTimes() const;
  /// The channel id advertised for `topic`, or -1.
  int64_t channel(const std::string& topic) const;
  void subscribe(uint32_t subscription, uint32_t channel);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<nlohmann::json> texts_;
  std::vector<std::vector<uint8_t>> frames_;
  std::vector<int64_t> frame_times_;
  std::atomic<bool> open_{false}, failed_{false}, closed_{false};
  std::atomic<int> http_status_{0};
  std::atomic<std::chrono::milliseconds::rep> delay_{0};
};

}  // namespace auv::foxglove_bridge::test
