#include "auv/interfaces/clock.h"

#include <chrono>

namespace auv::interfaces {

int64_t Clock::nowNs() const {
  if (source_ == Source::SIMULATION) return sim_ns_.load();
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

void Clock::setSimulationTime(int64_t ns) {
  if (source_ == Source::SIMULATION) sim_ns_.store(ns);
}

}  // namespace auv::interfaces
