#pragma once

#include "launch_description.h"

#include <sys/types.h>
#include <unistd.h>

#include <atomic>
#include <string>
#include <vector>

namespace auv::bringup {

/// Settings of a Supervisor that do not come from the launch file.
struct SupervisorOptions {
  std::string auv_executable;     // program run for components and for "auv" in commands
  int stdout_fd = STDOUT_FILENO;  // receives the children's stdout lines, "[name] " prefixed
  int stderr_fd = STDERR_FILENO;  // receives the children's stderr lines, "[name] " prefixed
  int log_fd = STDERR_FILENO;     // receives the supervisor's "[launch] ..." lines and summary
  bool handle_signals = true;     // SIGINT/SIGTERM/SIGHUP to this process start the shutdown
  bool reap_orphans = true;       // become child subreaper (Linux) so that leftovers of a
                                  // process group are reaped here even if they daemonized
  std::string temp_dir;           // parent of the inline params folder; "" = $TMPDIR or /tmp
  double poll_interval = 0.1;     // [s] longest sleep of the event loop (safety net)

  /// Throws std::invalid_argument naming the bad field and value.
  void check() const;
};

/// Why Supervisor::run() stopped its processes.
enum class LaunchEnd {
  ALL_EXITED,       // every process exited and none is due for a restart
  REQUIRED_EXITED,  // a required process exited for good
  SIGNAL,           // SIGINT/SIGTERM/SIGHUP to the launcher or requestShutdown()
};

/// How the last run of a process ended.
enum class ProcessOutcome {
  EXITED,        // exit() with exit_code
  SIGNALED,      // killed by signal `signal`
  START_FAILED,  // could not be spawned (e.g. program not found); counts as exit code 127
};

/// What happened to one process over the launch.
struct ProcessReport {
  std::string name;
  bool required = false;
  ProcessOutcome outcome = ProcessOutcome::START_FAILED;
  int exit_code = 0;              // EXITED: the exit status
  int signal = 0;                 // SIGNALED: the terminating signal
  std::string start_error;        // START_FAILED: why
  int restarts = 0;               // times it was started again after exiting
  bool stopped = false;           // its last run was ended by the launcher's shutdown
  int strongest_stop_signal = 0;  // last signal the shutdown sent it (SIGINT/SIGTERM/SIGKILL)
  std::vector<pid_t> pids;        // every pid it ran as, in order (all reaped by the end)

  /// True when the last run exited 0 or was stopped by the launcher.
  bool succeeded() const;
  /// "exited with code 3", "killed by SIGKILL", "failed to start: ...", prefixed with
  /// "stopped with SIGTERM, " when the launcher stopped it ("not started" if it never ran).
  std::string describe() const;
};

/// Result of Supervisor::run().
struct LaunchReport {
  int exit_code = 0;  // 0, or the first failure among the processes that count (see run())
  LaunchEnd end = LaunchEnd::ALL_EXITED;
  std::vector<ProcessReport> processes;  // in launch file order

  const ProcessReport* find(const std::string& name) const;  // nullptr when unknown
};

/// Starts and supervises the processes of a LaunchDescription, like `ros2 launch`.
///
/// Every process runs in its own process group with stdin from /dev/null; its stdout and
/// stderr are read through pipes and copied line by line, prefixed with "[name] ", to
/// SupervisorOptions::stdout_fd / stderr_fd. Exited processes are restarted according to
/// their policy. When a required process exits for good, on SIGINT/SIGTERM/SIGHUP (if
/// handle_signals) or requestShutdown(), every running process group gets SIGINT, then
/// SIGTERM after shutdown_timeout, then SIGKILL after another shutdown_timeout; another
/// signal or request skips to the next step. run() returns only after every child and every
/// leftover of the children's process groups has been reaped.
///
/// Only one Supervisor may be running in a process at a time (signal handlers are global).
class Supervisor {
 public:
  /// Validates `launch` (LaunchDescription::check()) and `options`; throws on bad input.
  Supervisor(LaunchDescription launch, SupervisorOptions options);
  ~Supervisor();
  Supervisor(const Supervisor&) = delete;
  Supervisor& operator=(const Supervisor&) = delete;

  /// Runs the launch to its end. Exit code: 0 when every required process (every process if
  /// none is required) last exited 0 or was stopped by the launcher; otherwise the status of
  /// the first one that failed (exit code, 128 + signal, or 127 when it could not start).
  /// Throws std::runtime_error if the launch cannot be set up (pipes, temp files) or if
  /// called twice.
  LaunchReport run();

  /// Starts (or, called again, escalates) the shutdown as if SIGINT had been received.
  /// Async-signal-safe and thread-safe; callable before or during run().
  void requestShutdown();

  const LaunchDescription& launch() const { return launch_; }
  const SupervisorOptions& options() const { return options_; }

 private:
  LaunchDescription launch_;
  SupervisorOptions options_;
  int wake_pipe_[2] = {-1, -1};  // self-pipe: signal handlers and requestShutdown() write here
  std::atomic<bool> started_{false};
};

}  // namespace auv::bringup
