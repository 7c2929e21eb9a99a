#pragma once
// What an executor runs: subscriptions, services and timers of nodes. Middleware threads
// only mark work ready and wake the executor; user callbacks run on executor threads, one at
// a time per executor, so components need no locks of their own. (The one opt-out is a
// subscription created with CallbackThread::MIDDLEWARE, see subscription.h.)

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>

namespace auv::interfaces {

/// A wake-up signal with an optional forward: a node's waker forwards to its executor's.
/// A waker that forwards is never waited on itself and keeps no pending state: every
/// notify() is passed on, so the target sees each edge. A waker without a forward only
/// broadcasts on the false -> true edge of its pending flag: while a wake-up is pending the
/// waiter is bound to re-check, so further notifications cost a lock and no futex call.
class Waker {
 public:
  void notify();
  /// Waits until notified or `deadline`; consumes the notification. Returns true if it was
  /// notified, false on timeout.
  bool waitUntil(std::chrono::steady_clock::time_point deadline);
  /// Forwards every later notify() to `target` (nullptr: stop forwarding). A notification
  /// pending here is handed on to `target`.
  void forwardTo(std::shared_ptr<Waker> target);

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  bool pending_ = false;  // only used while forward_ is null
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
