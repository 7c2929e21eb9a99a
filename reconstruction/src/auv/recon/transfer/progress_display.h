#pragma once
// The pull's progress for a person: on a terminal one redrawn bar with rate and ETA; otherwise
// (logs, CI) a plain line every few seconds.

#include <chrono>
#include <cstdio>
#include <deque>
#include <string>
#include <utility>

#include "auv/recon/transfer/puller.h"

namespace auv::recon::transfer {

class ProgressDisplay {
 public:
  /// Writes to `out`; `tty` chooses the redrawn bar.
  ProgressDisplay(std::FILE* out, bool tty, double plain_period_s = 5.0);
  void update(const PullProgress& progress);
  /// A line of its own (clears the bar first).
  void message(const std::string& text);
  /// Clears the bar before the summary.
  void finish();

  /// "12.3 MiB" style.
  static std::string bytes(double value);
  /// "1:02:03" / "2:03" / "5 s".
  static std::string duration(double seconds);

 private:
  std::string line(const PullProgress& progress, int bar_width);

  std::FILE* out_;
  bool tty_;
  double plain_period_s_;
  bool bar_shown_ = false;
  std::chrono::steady_clock::time_point last_plain_;
  std::deque<std::pair<std::chrono::steady_clock::time_point, uint64_t>> samples_;  // for rate
};

}  // namespace auv::recon::transfer
