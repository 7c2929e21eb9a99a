#pragma once
// The time components read: the system clock, or the simulation clock published on `clock`
// (so simulated missions run faster than real time, like ROS's use_sim_time).

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>

namespace auv::interfaces {

class Clock {
 public:
  enum class Source { SYSTEM, SIMULATION };

  explicit Clock(Source source = Source::SYSTEM) : source_(source) {}
  Source source() const { return source_; }
  /// Nanoseconds since the epoch of the source (Unix epoch, or simulation start). A
  /// simulation clock reads 0 until its first `clock` message.
  int64_t nowNs() const;
  double nowSeconds() const { return static_cast<double>(nowNs()) * 1e-9; }
  /// Advances a simulation clock (called when a `clock` message arrives). Ignored for SYSTEM.
  void setSimulationTime(int64_t ns);
  /// True once a simulation clock has received time (always true for SYSTEM).
  bool valid() const { return source_ == Source::SYSTEM || sim_ns_.load() > 0; }

 private:
  Source source_;
  std::atomic<int64_t> sim_ns_{0};
};

}  // namespace auv::interfaces
