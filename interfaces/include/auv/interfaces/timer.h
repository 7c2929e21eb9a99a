#pragma once

#include <cstdint>
#include <functional>

#include "auv/interfaces/clock.h"
#include "auv/interfaces/waitable.h"

namespace auv::interfaces {

/// Calls back every `period` of the node's clock (system or simulation time). A timer that
/// falls behind skips the missed periods rather than firing in a burst.
class Timer : public Waitable {
 public:
  Timer(const Clock& clock, int64_t period_ns, std::function<void()> callback);
  bool execute() override;
  std::optional<int64_t> nanosecondsUntilDue() const override;
  void cancel() { cancelled_ = true; }
  int64_t periodNs() const { return period_ns_; }

 private:
  const Clock& clock_;
  int64_t period_ns_;
  std::function<void()> callback_;
  int64_t next_due_ns_ = -1;  // set at the first check, when the clock is valid
  bool cancelled_ = false;
};

}  // namespace auv::interfaces
