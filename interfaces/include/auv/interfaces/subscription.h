#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <string>

#include "auv/interfaces/backend.h"
#include "auv/interfaces/waitable.h"

namespace auv::interfaces {

/// Which thread runs a subscription's callback.
enum class CallbackThread {
  /// The executor spinning the node (default): callbacks of one executor run one at a time,
  /// so a component needs no locks. Costs a wake-up of the executor thread per burst.
  EXECUTOR,
  /// The vendor's listener thread, as soon as data arrives: no hand-off, for latency-critical
  /// relays. Runs concurrently with the executor's callbacks; see Node::createSubscription.
  /// Not for large messages: taking them in the listener holds up the vendor's receive
  /// thread (benchmark, Cyclone, 4 MiB best effort: 93 % of samples lost, EXECUTOR <= 1.3 %).
  MIDDLEWARE,
};

/// Per-subscription options of Node::createSubscription.
struct SubscriptionOptions {
  CallbackThread callback_thread = CallbackThread::EXECUTOR;  ///< Where the callback runs.
};

/// Receives messages of type T. Keeps samples in DDS (bounded by the QoS history) until they
/// are taken: by the executor that spins the node (CallbackThread::EXECUTOR), or directly in
/// the vendor's listener thread (CallbackThread::MIDDLEWARE).
template <class T>
class Subscription : public Waitable {
 public:
  using Callback = std::function<void(const T& message, const SampleInfo& info)>;

  Subscription(std::string topic, QosProfile qos, Callback callback,
               CallbackThread callback_thread = CallbackThread::EXECUTOR)
      : topic_(std::move(topic)),
        qos_(std::move(qos)),
        callback_(std::move(callback)),
        callback_thread_(callback_thread),
        ready_(callback_thread == CallbackThread::EXECUTOR) {}
  /// Called by the node once the reader exists.
  void attach(std::unique_ptr<DataReader> reader) { reader_ = std::move(reader); }
  /// Samples one execute() takes at most. A flooded topic must not hold up the rest of the
  /// executor's work (timers, services, the other components composed in the process) for a
  /// whole backlog; what is left is taken on the executor's next round, without waiting.
  static constexpr int kMaxSamplesPerExecute = 32;

  /// Set from a middleware thread when data arrives (executor mode). Returns true if it was
  /// not ready yet: only then does the executor need a wake-up (a ready subscription is
  /// already due to be executed, and stays ready until a take finds nothing).
  bool markReady() { return !ready_.exchange(true); }

  /// Executor mode: takes up to kMaxSamplesPerExecute samples and calls back, on the
  /// executor's thread.
  bool execute() override {
    if (!ready_.exchange(false)) return false;
    bool more = true;
    try {
      more = take(*reader_, kMaxSamplesPerExecute);
    } catch (...) {  // a throwing callback: the samples behind it wait for the next round
      ready_ = true;
      throw;
    }
    if (more) ready_ = true;
    return true;
  }
  /// Middleware mode: called by the vendor's listener (never concurrently for one reader:
  /// both vendors serialize listener calls per reader); takes and calls back right there.
  void onData(DataReader& reader) { take(reader, -1); }

  /// Publishers currently matched, of both vendors.
  int matchedPublishers() const { return reader_->matchedWriters(); }
  const std::string& topic() const { return topic_; }
  const QosProfile& qos() const { return qos_; }
  CallbackThread callbackThread() const { return callback_thread_; }

 private:
  /// Takes and calls back until nothing is left or `limit` samples were taken (< 0: no
  /// limit); returns true if it stopped at the limit.
  bool take(DataReader& reader, int limit) {
    const auto visit = [this](const void* sample, const SampleInfo& info) {
      callback_(*static_cast<const T*>(sample), info);
    };
    for (int taken = 0; limit < 0 || taken < limit;) {
      const int batch = limit < 0 ? DataReader::kMaxBatch : limit - taken;
      // message_ is the scratch sample: deserialization overwrites every field, and keeping
      // its buffers saves an allocation per sample (measured in docs/performance.md).
      const int n = reader.takeBatch(&message_, batch, visit);
      if (n == 0) return false;
      taken += n;
    }
    return true;
  }

  std::string topic_;
  QosProfile qos_;
  Callback callback_;
  CallbackThread callback_thread_;
  T message_;  // reused by take(), which only ever runs on one thread at a time
  // Executor mode starts ready: a transient-local history may be waiting at creation.
  std::atomic<bool> ready_;
  std::unique_ptr<DataReader> reader_;  // last: destroyed first, before what its callback uses
};

}  // namespace auv::interfaces
