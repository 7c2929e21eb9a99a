#include "auv/interfaces/waitable.h"

#include "auv/interfaces/timer.h"

namespace auv::interfaces {

void Waker::notify() {
  std::shared_ptr<Waker> forward;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    pending_ = true;
    forward = forward_;
  }
  cv_.notify_all();
  if (forward) forward->notify();
}

void Waker::waitUntil(std::chrono::steady_clock::time_point deadline) {
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait_until(lock, deadline, [this] { return pending_; });
  pending_ = false;
}

void Waker::forwardTo(std::shared_ptr<Waker> target) {
  std::lock_guard<std::mutex> lock(mutex_);
  forward_ = std::move(target);
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
