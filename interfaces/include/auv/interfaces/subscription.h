#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <string>

#include "auv/interfaces/backend.h"
#include "auv/interfaces/waitable.h"

namespace auv::interfaces {

/// Receives messages of type T; the callback runs on the executor that spins the node.
/// Keeps samples in DDS (bounded by the QoS history) until the executor takes them.
template <class T>
class Subscription : public Waitable {
 public:
  using Callback = std::function<void(const T& message, const SampleInfo& info)>;

  Subscription(std::string topic, QosProfile qos, Callback callback)
      : topic_(std::move(topic)), qos_(std::move(qos)), callback_(std::move(callback)) {}
  /// Called by the node once the reader exists.
  void attach(std::unique_ptr<DataReader> reader) { reader_ = std::move(reader); }
  /// Set from a middleware thread when data arrives.
  void markReady() { ready_ = true; }

  bool execute() override {
    if (!ready_.exchange(false)) return false;
    SampleInfo info;
    // One message reused: deserialization overwrites every field, and keeping its buffers
    // saves an allocation per sample (measured in docs/performance.md).
    while (reader_->take(&message_, &info)) callback_(message_, info);
    return true;
  }
  /// Publishers currently matched, of both vendors.
  int matchedPublishers() const { return reader_->matchedWriters(); }
  const std::string& topic() const { return topic_; }
  const QosProfile& qos() const { return qos_; }

 private:
  std::string topic_;
  QosProfile qos_;
  Callback callback_;
  T message_;                           // reused by execute()
  std::atomic<bool> ready_{true};       // a transient-local history may be waiting at creation
  std::unique_ptr<DataReader> reader_;  // last: destroyed first, before what its callback uses
};

}  // namespace auv::interfaces
