#pragma once
// Nanosecond stamps (Clock::nowNs(), simulation or system epoch) <-> auv::msg::Time.

#include <cstdint>

#include "auv/msg/all.h"

namespace auv::interfaces {

inline msg::Time toMsgTime(int64_t ns) {
  int64_t sec = ns / 1000000000;
  int64_t rest = ns % 1000000000;
  if (rest < 0) sec -= 1, rest += 1000000000;  // nanosec is always in [0, 1e9)
  msg::Time time;
  time.sec(static_cast<int32_t>(sec));
  time.nanosec(static_cast<uint32_t>(rest));
  return time;
}

inline int64_t toNanoseconds(const msg::Time& time) {
  return static_cast<int64_t>(time.sec()) * 1000000000 + static_cast<int64_t>(time.nanosec());
}

}  // namespace auv::interfaces
