#pragma once

#include <signal.h>

#include <string>
#include <utility>
#include <vector>

namespace auv::bringup {

/// Wake byte of Supervisor::requestShutdown(); signal handlers write the signal's number.
constexpr unsigned char kShutdownRequestByte = 0;

/// "SIGTERM", or "signal 42" for a number without a name here.
std::string signalName(int signal_number);

/// For its lifetime: SIGCHLD (and SIGINT/SIGTERM/SIGHUP with `handle_signals`) each write one
/// byte, the signal's number, to `wake_fd`; SIGPIPE is ignored; with `subreaper` this process
/// becomes a child subreaper (Linux) so that leftovers of a child's process group are reaped
/// here even if they daemonized. The destructor restores all of it, however the caller ends.
/// Signal handlers are global, so only one guard may exist at a time: a second one throws.
class ProcessStateGuard {
 public:
  ProcessStateGuard(int wake_fd, bool handle_signals, bool subreaper);
  ~ProcessStateGuard();

  ProcessStateGuard(const ProcessStateGuard&) = delete;
  ProcessStateGuard& operator=(const ProcessStateGuard&) = delete;

 private:
  using sigaction_t = struct sigaction;

  void install(int signal_number, int flags);

  std::vector<std::pair<int, sigaction_t>> saved_;
  sigset_t saved_mask_{};
  int saved_subreaper_ = 0;
  bool subreaper_set_ = false;
};

}  // namespace auv::bringup
