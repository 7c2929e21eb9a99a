#pragma once
// Progress of a long stage for a person: on a terminal one redrawn line with a bar, rate and
// ETA; otherwise (logs, CI) a plain line every few seconds. Thread-safe: OpenMP loops advance
// it from every thread.

#include <chrono>
#include <cstdio>
#include <mutex>
#include <string>

namespace auv::recon {

class Progress {
 public:
  enum class Mode { AUTO, BAR, PLAIN, QUIET };

  /// `what` names the work ("keyframes left"), `unit` what is counted ("frames").
  /// AUTO: BAR when `out` is a terminal, else PLAIN; the environment variable
  /// AUV_PROGRESS=bar|plain|quiet overrides it.
  Progress(std::string what, std::string unit, size_t total, Mode mode = Mode::AUTO,
           std::FILE* out = stderr);
  ~Progress();  ///< finish()
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void advance(size_t count = 1);
  void setTotal(size_t total);
  /// A line of its own (clears the bar first).
  void message(const std::string& text);
  /// Clears the bar and prints "<what>: <done> <unit> in <time> (<rate>/s)" once.
  void finish();

  size_t done() const;
  double seconds() const;

  /// "1:02:03" / "2:03" / "5 s".
  static std::string duration(double seconds);

 private:
  void drawLocked(bool force);

  std::string what_, unit_;
  size_t total_, done_ = 0;
  Mode mode_;
  std::FILE* out_;
  mutable std::mutex mutex_;
  std::chrono::steady_clock::time_point start_, last_draw_;
  bool bar_shown_ = false, finished_ = false;
};

}  // namespace auv::recon
