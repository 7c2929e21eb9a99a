#pragma once
// The bridge's DDS side for forwarded topics: a GraphInspector finds every topic with writers
// on the domain (either vendor) and each is advertised as a `cdr` channel with its type's OMG
// IDL (`omgidl`) schema; a topic whose writers are all gone is unadvertised. A serialized
// reader (on a participant of the forwarder's own, QoS from compatibleReaderQos) exists only
// while a client subscribes, and its samples go to the clients byte for byte. Topics of type
// CompressedImage also get a `/foxglove/camera/<name>` channel (foxglove.CompressedImage,
// JSON) served by the same reader.

#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "auv/foxglove_bridge/bridge_core.h"
#include "auv/interfaces/graph.h"
#include "auv/interfaces/serialized.h"

namespace auv::foxglove_bridge {

struct ForwarderOptions {
  std::vector<std::string> topics;   ///< forwarded topics; empty: all
  std::vector<std::string> exclude;  ///< never forwarded
  double discovery_period = 0.5;     ///< s between looks at the graph
  int32_t reader_depth = 100;        ///< keep-last depth of the serialized readers
};

class TopicForwarder {
 public:
  TopicForwarder(interfaces::Vendor vendor, int domain_id, ForwarderOptions options,
                 BridgeCore& core);
  ~TopicForwarder();
  void start();
  void stop();

  /// From the core's Listener: (re)creates or drops the reader behind `channel`. False when
  /// the channel is not one of the forwarder's.
  bool reconcile(uint32_t channel);
  /// Runs one discovery pass now (tests).
  void discoverNow();

  uint64_t forwardedSamples() const { return forwarded_; }
  /// Serialized DDS readers that exist now (one per topic a client subscribes to).
  size_t activeReaders() const;
  /// Topics skipped with the reason ("/x: type 'y' is not one of auv-inspect's messages").
  std::vector<std::string> skipped() const;

 private:
  struct Topic {
    std::string name;
    const msg::TypeSupport* type = nullptr;
    uint32_t channel = 0;         // the cdr channel
    uint32_t camera_channel = 0;  // the foxglove.CompressedImage channel, 0: none
    interfaces::QosProfile qos;
    bool droppable = false;               // best-effort writers: a slow client may lose samples
    interfaces::SerializedSample sample;  // reused by the reader's callback
    std::unique_ptr<interfaces::SerializedReader> reader;
  };
  void loop();
  void onSamples(Topic& topic, interfaces::SerializedReader& reader);
  bool wanted(const std::string& topic) const;

  interfaces::Vendor vendor_;
  int domain_id_;
  ForwarderOptions options_;
  BridgeCore& core_;
  std::unique_ptr<interfaces::Participant> participant_;
  std::unique_ptr<interfaces::GraphInspector> inspector_;
  mutable std::mutex mutex_;  // topics_, skipped_; never held by a reader callback
  std::map<std::string, std::unique_ptr<Topic>> topics_;
  std::map<std::string, std::string> skipped_;
  std::atomic<bool> running_{false};
  std::atomic<uint64_t> forwarded_{0};
  std::thread thread_;
};

}  // namespace auv::foxglove_bridge
