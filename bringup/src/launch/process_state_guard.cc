#include "process_state_guard.h"

#include <unistd.h>
#ifdef __linux__
#include <sys/prctl.h>
#endif

#include <atomic>
#include <cerrno>
#include <stdexcept>

namespace auv::bringup {
namespace {

// Signal handlers only see globals: the write end of the running Supervisor's self-pipe.
std::atomic<int> g_wake_fd{-1};
std::atomic<bool> g_guard_active{false};

void onSignal(int signal_number) {
  const int saved_errno = errno;
  const int fd = g_wake_fd.load();
  if (fd >= 0) {
    const auto byte = static_cast<unsigned char>(signal_number);
    [[maybe_unused]] const ssize_t written = write(fd, &byte, 1);
  }
  errno = saved_errno;
}

}  // namespace

std::string signalName(int signal_number) {
  static constexpr std::pair<int, const char*> kNames[] = {
      {SIGHUP, "SIGHUP"},   {SIGINT, "SIGINT"},   {SIGQUIT, "SIGQUIT"}, {SIGILL, "SIGILL"},
      {SIGTRAP, "SIGTRAP"}, {SIGABRT, "SIGABRT"}, {SIGBUS, "SIGBUS"},   {SIGFPE, "SIGFPE"},
      {SIGKILL, "SIGKILL"}, {SIGUSR1, "SIGUSR1"}, {SIGSEGV, "SIGSEGV"}, {SIGUSR2, "SIGUSR2"},
      {SIGPIPE, "SIGPIPE"}, {SIGALRM, "SIGALRM"}, {SIGTERM, "SIGTERM"}, {SIGCHLD, "SIGCHLD"}};
  for (const auto& [number, name] : kNames) {
    if (number == signal_number) return name;
  }
  return "signal " + std::to_string(signal_number);
}

ProcessStateGuard::ProcessStateGuard(int wake_fd, bool handle_signals, bool subreaper) {
  if (g_guard_active.exchange(true)) {
    throw std::runtime_error("Supervisor: another Supervisor is already running");
  }
  g_wake_fd.store(wake_fd);
  install(SIGCHLD, SA_RESTART | SA_NOCLDSTOP);
  if (handle_signals) {
    for (int signal_number : {SIGINT, SIGTERM, SIGHUP}) install(signal_number, SA_RESTART);
  }
  struct sigaction ignore {};
  ignore.sa_handler = SIG_IGN;
  sigemptyset(&ignore.sa_mask);
  saved_.emplace_back(SIGPIPE, sigaction_t{});
  sigaction(SIGPIPE, &ignore, &saved_.back().second);
  // Unblock what we handle, in case the caller blocked it.
  sigset_t handled;
  sigemptyset(&handled);
  for (const auto& entry : saved_) sigaddset(&handled, entry.first);
  pthread_sigmask(SIG_UNBLOCK, &handled, &saved_mask_);
#ifdef __linux__
  if (subreaper && prctl(PR_GET_CHILD_SUBREAPER, &saved_subreaper_) == 0 &&
      prctl(PR_SET_CHILD_SUBREAPER, 1) == 0) {
    subreaper_set_ = true;
  }
#else
  (void)subreaper;
#endif
}

ProcessStateGuard::~ProcessStateGuard() {
#ifdef __linux__
  if (subreaper_set_) prctl(PR_SET_CHILD_SUBREAPER, saved_subreaper_);
#endif
  pthread_sigmask(SIG_SETMASK, &saved_mask_, nullptr);
  for (auto it = saved_.rbegin(); it != saved_.rend(); ++it) {
    sigaction(it->first, &it->second, nullptr);
  }
  g_wake_fd.store(-1);
  g_guard_active.store(false);
}

void ProcessStateGuard::install(int signal_number, int flags) {
  struct sigaction action {};
  action.sa_handler = onSignal;
  action.sa_flags = flags;
  sigemptyset(&action.sa_mask);
  saved_.emplace_back(signal_number, sigaction_t{});
  sigaction(signal_number, &action, &saved_.back().second);
}

}  // namespace auv::bringup
