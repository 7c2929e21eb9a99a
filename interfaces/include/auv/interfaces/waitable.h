#pragma once
// What an executor runs: subscriptions, services and timers of nodes. Middleware threads
// only mark work ready and wake the executor; user callbacks always run on executor threads,
// one at a time per executor, so components need no locks of their own.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>

namespace auv::interfaces {

/// A wake-up signal with an optional forward: a node's waker forwards to its executor's.
class Waker {
 public:
  void notify();
  /// Waits until notified or `deadline`; consumes the notification.
  void waitUntil(std::chrono::steady_clock::time_point deadline);
  void forwardTo(std::shared_ptr<Waker> target);

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  bool pending_ = false;
  std::shared_ptr<Waker> forward_;
};

class Waitable {
 public:
  virtual ~Waitable() = default;
  /// Runs whatever is ready (takes samples, fires due timers). Returns true if it did work.
  virtual bool execute() = 0;
  /// For timers: nanoseconds of steady time until the next due time, if any.
  virtual std::optional<int64_t> nanosecondsUntilDue() const { return std::nullopt; }
};

}  // namespace auv::interfaces
