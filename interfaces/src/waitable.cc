#include "auv/interfaces/waitable.h"

#include "auv/interfaces/timer.h"

#include <utility>

namespace auv::interfaces {

void Waker::notify() {
  std::unique_lock<std::mutex> lock(mutex_);
  if (forward_) {
    // Forwarding: nobody waits here, so there is no edge to detect; the target decides.
    std::shared_ptr<Waker> target = forward_;
    lock.unlock();
    target->notify();
    return;
  }
  if (pending_) return;  // the waiter has not consumed the last wake-up and will re-check
  pending_ = true;
  lock.unlock();
  cv_.notify_all();
}

bool Waker::waitUntil(std::chrono::steady_clock::time_point deadline) {
  std::unique_lock<std::mutex> lock(mutex_);
  const bool notified = cv_.wait_until(lock, deadline, [this] { return pending_; });
  pending_ = false;
  return notified;
}

void Waker::forwardTo(std::shared_ptr<Waker> target) {
  bool was_pending = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    forward_ = target;
    was_pending = std::exchange(pending_, false);
  }
  if (was_pending && target) target->notify();
}

Timer::Timer(const Clock& clock, int64_t period_ns, std::function<void()> callback)
    : clock_(clock), period_ns_(period_ns), callback_(std::move(callback)) {}

bool Timer::execute() {
  if (cancelled_ || !clock_.valid()) return false;
  const int64_t now = clock_.nowNs();
  if (next_due_ns_ < 0) next_due_ns_ = now + period_ns_;
  if (now < next_due_ns_) return false;
  next_due_ns_ += period_ns_;
  if (next_due_ns_ <= now) next_due_ns_ = now + period_ns_;  // fell behind: skip, no burst
  callback_();
  return true;
}

std::optional<int64_t> Timer::nanosecondsUntilDue() const {
  // Simulation time advances with `clock` messages, which wake the executor themselves.
  if (cancelled_ || clock_.source() != Clock::Source::SYSTEM) return std::nullopt;
  if (next_due_ns_ < 0) return 0;
  return std::max<int64_t>(0, next_due_ns_ - clock_.nowNs());
}

}  // namespace auv::interfaces
