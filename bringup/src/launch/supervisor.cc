#include "supervisor.h"

#include "child_process.h"
#include "process_command.h"
#include "process_state_guard.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <random>
#include <sstream>
#include <stdexcept>

extern char** environ;

namespace auv::bringup {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr int kStartFailedExitCode = 127;  // like a shell's "command not found"
constexpr int kLostStatusExitCode = 255;   // a child reaped by someone else

/// 64 random bits in hex: unique per launch on this machine and across reboots.
std::string newLaunchId() {
  std::random_device random;
  const uint64_t id = (static_cast<uint64_t>(random()) << 32) ^ random();
  std::ostringstream out;
  out << std::hex << std::setw(16) << std::setfill('0') << id;
  return out.str();
}

Clock::duration toDuration(double seconds) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

std::string formatSeconds(double seconds) {
  std::ostringstream out;
  out.precision(3);
  out << seconds << " s";
  return out.str();
}

// Folder for generated params files, removed with everything in it on destruction.
class TempDir {
 public:
  TempDir() = default;
  ~TempDir() {
    if (!path_.empty()) {
      std::error_code error;
      fs::remove_all(path_, error);
    }
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::string& create(const std::string& parent) {
    std::string pattern = (fs::path(parent) / "auv-launch-XXXXXX").string();
    if (mkdtemp(pattern.data()) == nullptr) {
      throw std::runtime_error("Supervisor: cannot create a folder in " + parent + ": " +
                               std::strerror(errno));
    }
    path_ = pattern;
    return path_;
  }

 private:
  std::string path_;
};

enum class State { RUNNING, WAITING_RESTART, FINISHED };

// Run-time state of one launch process.
struct Child {
  const ProcessDescription* process = nullptr;
  ProcessCommand command;
  std::vector<std::string> environment;  // full "NAME=value" list for exec
  std::string program;                   // argv[0] resolved in the child's PATH
  State state = State::FINISHED;
  pid_t pid = -1;
  OutputStream out;
  OutputStream err;
  bool stop_sent = false;  // the current run got a shutdown signal
  Clock::time_point restart_at;
  long finish_order = -1;  // order in which processes finished for good
  ProcessReport report;
};

// The event loop of one Supervisor::run().
class Run {
 public:
  Run(const LaunchDescription& launch, const SupervisorOptions& options, int wake_fd)
      : launch_(launch), options_(options), wake_fd_(wake_fd) {}

  ~Run() {
    // Safety net if run() is left by an exception: nothing may outlive us unreaped.
    for (Child& child : children_) {
      if (child.state == State::RUNNING && child.pid > 0) {
        signalGroup(child.pid, SIGKILL);
        int status = 0;
        while (waitpid(child.pid, &status, 0) < 0 && errno == EINTR) {
        }
        orphan_groups_.push_back(child.pid);
      }
      closeFd(child.out.fd);
      closeFd(child.err.fd);
    }
    reapOrphanGroups(/*block=*/true);
  }

  Run(const Run&) = delete;
  Run& operator=(const Run&) = delete;

  LaunchReport execute(const std::string& auv_executable) {
    prepare(auv_executable);
    if (drainWakePipe()) {  // requestShutdown() before run(): start nothing
      shutting_down_ = true;
      end_ = LaunchEnd::SIGNAL;
      log("shutdown requested before start; not starting any process");
    }
    for (Child& child : children_) {
      if (shutting_down_) {
        child.report.stopped = true;
        finish(child);
        continue;
      }
      start(child);
    }
    loop();
    reapOrphanGroups(/*block=*/true);
    return report();
  }

 private:
  void prepare(const std::string& auv_executable) {
    const std::string parent_dir = tempParent();
    std::string params_dir;
    children_.resize(launch_.processes.size());
    const std::string launch_id = newLaunchId();
    for (size_t i = 0; i < launch_.processes.size(); ++i) {
      Child& child = children_[i];
      child.process = &launch_.processes[i];
      child.report.name = child.process->name;
      child.report.required = child.process->required;
      child.report.outcome = ProcessOutcome::START_FAILED;
      child.report.start_error = "not started";
      if (params_dir.empty() && !inlineParametersYaml(*child.process).empty()) {
        params_dir = temp_dir_.create(parent_dir);
      }
      child.command = buildProcessCommand(launch_, *child.process, auv_executable, params_dir);
      if (!child.command.inline_params_path.empty()) {
        std::ofstream file(child.command.inline_params_path);
        file << child.command.inline_params_yaml;
        if (!file) {
          throw std::runtime_error("Supervisor: cannot write " + child.command.inline_params_path);
        }
      }
      // One id for the whole launch, kept across restarts: what a restarted process may
      // resume (auv/config/state_file.h). An exported AUV_LAUNCH_ID resumes an earlier launch.
      if (!std::getenv("AUV_LAUNCH_ID")) child.command.environment["AUV_LAUNCH_ID"] = launch_id;
      child.environment = mergeEnvironment(environ, child.command.environment);
      std::string path_variable;
      for (const std::string& entry : child.environment) {
        if (entry.rfind("PATH=", 0) == 0) path_variable = entry.substr(5);
      }
      child.program = findExecutable(child.command.argv[0], path_variable);
    }
    name_width_ = 0;
    for (const Child& child : children_) {
      name_width_ = std::max(name_width_, child.process->name.size());
    }
  }

  std::string tempParent() const {
    if (!options_.temp_dir.empty()) return options_.temp_dir;
    const char* tmpdir = std::getenv("TMPDIR");
    return tmpdir != nullptr && *tmpdir != '\0' ? tmpdir : "/tmp";
  }

  void log(const std::string& message) const {
    writeAll(options_.log_fd, "[launch] " + message + "\n");
  }

  // Spawns the child in its own process group with stdin=/dev/null and piped stdout/stderr.
  void start(Child& child) {
    child.stop_sent = false;
    child.out.partial.clear();
    child.err.partial.clear();
    if (child.program.empty()) {
      startFailed(child, "program '" + child.command.argv[0] + "' not found in PATH");
      return;
    }
    const SpawnedChild spawned =
        spawnInOwnGroup(child.program, child.command.argv, child.environment);
    if (spawned.error != 0) {
      startFailed(child, child.program + ": " + std::strerror(spawned.error));
      return;
    }
    child.out = OutputStream{spawned.stdout_fd, options_.stdout_fd, ""};
    child.err = OutputStream{spawned.stderr_fd, options_.stderr_fd, ""};
    child.pid = spawned.pid;
    child.state = State::RUNNING;
    child.report.pids.push_back(spawned.pid);
    log("started " + child.process->name + " (pid " + std::to_string(spawned.pid) + ")");
  }

  void startFailed(Child& child, const std::string& why) {
    child.report.outcome = ProcessOutcome::START_FAILED;
    child.report.start_error = why;
    child.report.stopped = false;
    child.pid = -1;
    log(child.process->name + ": failed to start: " + why);
    // Not restarted: a missing program or a bad argv will not fix itself.
    finish(child);
    if (child.process->required && !shutting_down_) {
      log("required process " + child.process->name + " could not start; shutting down");
      beginShutdown(LaunchEnd::REQUIRED_EXITED);
    }
  }

  void finish(Child& child) {
    child.state = State::FINISHED;
    child.finish_order = next_finish_order_++;
  }

  void loop() {
    while (true) {
      reapChildren();
      reapOrphanGroups(/*block=*/false);
      startDueRestarts();
      if (shutting_down_ && stage_ < 3 && runningCount() > 0 && Clock::now() >= stage_deadline_) {
        log(std::to_string(runningCount()) + " process(es) still running after " +
            formatSeconds(launch_.shutdown_timeout) + ": " + runningNames() + "; sending " +
            signalName(kStageSignals[stage_]));
        escalate();
        continue;
      }
      if (!anyActive()) break;
      waitForEvents();
    }
  }

  bool anyActive() const {
    return std::any_of(children_.begin(), children_.end(),
                       [](const Child& child) { return child.state != State::FINISHED; });
  }

  size_t runningCount() const {
    return std::count_if(children_.begin(), children_.end(),
                         [](const Child& child) { return child.state == State::RUNNING; });
  }

  std::string runningNames() const {
    std::string names;
    for (const Child& child : children_) {
      if (child.state == State::RUNNING) names += (names.empty() ? "" : ", ") + child.process->name;
    }
    return names;
  }

  // Sleeps in poll() until output, a signal, a child exit or the next deadline.
  void waitForEvents() {
    Clock::time_point deadline = Clock::now() + toDuration(options_.poll_interval);
    if (shutting_down_ && stage_ < 3) deadline = std::min(deadline, stage_deadline_);
    for (const Child& child : children_) {
      if (child.state == State::WAITING_RESTART) deadline = std::min(deadline, child.restart_at);
    }
    const auto remaining =
        std::chrono::duration_cast<std::chrono::microseconds>(deadline - Clock::now());
    const int timeout_ms =
        remaining.count() <= 0 ? 0 : static_cast<int>((remaining.count() + 999) / 1000);

    std::vector<pollfd> fds;
    std::vector<OutputStream*> streams;
    fds.push_back({wake_fd_, POLLIN, 0});
    streams.push_back(nullptr);
    for (Child& child : children_) {
      for (OutputStream* stream : {&child.out, &child.err}) {
        if (stream->fd < 0) continue;
        fds.push_back({stream->fd, POLLIN, 0});
        streams.push_back(stream);
      }
    }
    const int ready = poll(fds.data(), fds.size(), timeout_ms);
    if (ready <= 0) return;  // timeout or EINTR: the loop re-checks everything
    if (fds[0].revents & POLLIN) handleWakeBytes();
    for (size_t i = 1; i < fds.size(); ++i) {
      if (fds[i].revents & (POLLIN | POLLHUP | POLLERR)) {
        readAvailable(*streams[i], prefixOf(*streams[i]));
      }
    }
  }

  std::string prefixOf(const OutputStream& stream) const {
    for (const Child& child : children_) {
      if (&child.out == &stream || &child.err == &stream) return "[" + child.process->name + "] ";
    }
    return "";
  }

  // Returns true if the pipe held a shutdown request (used before the start).
  bool drainWakePipe() {
    bool stop = false;
    unsigned char bytes[256];
    ssize_t n;
    while ((n = read(wake_fd_, bytes, sizeof(bytes))) > 0) {
      for (ssize_t i = 0; i < n; ++i) stop |= bytes[i] != SIGCHLD;
    }
    return stop;
  }

  void handleWakeBytes() {
    unsigned char bytes[256];
    ssize_t n;
    while ((n = read(wake_fd_, bytes, sizeof(bytes))) > 0) {
      for (ssize_t i = 0; i < n; ++i) {
        if (bytes[i] == SIGCHLD) continue;  // exits are collected by reapChildren()
        const std::string what = bytes[i] == kShutdownRequestByte ? std::string("shutdown request")
                                                                  : signalName(bytes[i]);
        if (!shutting_down_) {
          log("received " + what + "; stopping " + std::to_string(runningCount()) +
              " process(es): SIGINT, SIGTERM after " + formatSeconds(launch_.shutdown_timeout) +
              ", then SIGKILL");
          beginShutdown(LaunchEnd::SIGNAL);
        } else if (stage_ < 3) {
          log("received " + what + " again; sending " + signalName(kStageSignals[stage_]) + " now");
          escalate();
        }
      }
    }
  }

  void reapChildren() {
    for (Child& child : children_) {
      if (child.state != State::RUNNING) continue;
      int status = 0;
      pid_t result;
      do {
        result = waitpid(child.pid, &status, WNOHANG);
      } while (result < 0 && errno == EINTR);
      if (result == child.pid) {
        onExit(child, status);
      } else if (result < 0 && errno == ECHILD) {
        // Someone else in this process reaped it (e.g. a waitpid(-1) elsewhere).
        log(child.process->name + " (pid " + std::to_string(child.pid) +
            ") was reaped outside the launcher; its exit status is lost");
        onExit(child, W_EXITCODE(kLostStatusExitCode, 0));
      }
    }
  }

  void onExit(Child& child, int status) {
    const pid_t pid = child.pid;
    // Whatever is left in its process group dies with it (and is reaped later).
    kill(-pid, SIGKILL);
    orphan_groups_.push_back(pid);
    child.pid = -1;
    const std::string prefix = "[" + child.process->name + "] ";
    drainAndClose(child.out, prefix);
    drainAndClose(child.err, prefix);

    ProcessReport& report = child.report;
    report.start_error.clear();
    report.stopped = child.stop_sent;
    if (WIFSIGNALED(status)) {
      report.outcome = ProcessOutcome::SIGNALED;
      report.signal = WTERMSIG(status);
      report.exit_code = 0;
    } else {
      report.outcome = ProcessOutcome::EXITED;
      report.exit_code = WEXITSTATUS(status);
      report.signal = 0;
    }
    const ProcessDescription& process = *child.process;
    std::string message = process.name + " (pid " + std::to_string(pid) + ") " + report.describe();

    const bool failed = report.outcome != ProcessOutcome::EXITED || report.exit_code != 0;
    const bool policy_restarts = process.restart == RestartPolicy::ALWAYS ||
                                 (process.restart == RestartPolicy::ON_FAILURE && failed);
    const bool budget_left = !process.max_restarts || report.restarts < *process.max_restarts;
    if (shutting_down_) {
      log(message);
      finish(child);
    } else if (policy_restarts && budget_left) {
      child.state = State::WAITING_RESTART;
      child.restart_at = Clock::now() + toDuration(process.restart_delay);
      const std::string budget =
          process.max_restarts ? " of " + std::to_string(*process.max_restarts) : "";
      log(message + "; restarting in " + formatSeconds(process.restart_delay) + " (restart " +
          std::to_string(report.restarts + 1) + budget + ")");
    } else {
      if (policy_restarts) message += "; max_restarts reached";
      log(message);
      finish(child);
      if (process.required) {
        log("required process " + process.name + " ended; shutting down");
        beginShutdown(LaunchEnd::REQUIRED_EXITED);
      }
    }
  }

  void startDueRestarts() {
    const Clock::time_point now = Clock::now();
    for (Child& child : children_) {
      if (child.state == State::WAITING_RESTART && now >= child.restart_at && !shutting_down_) {
        ++child.report.restarts;
        start(child);
      }
    }
  }

  void beginShutdown(LaunchEnd reason) {
    if (shutting_down_) return;
    shutting_down_ = true;
    end_ = reason;
    for (Child& child : children_) {
      if (child.state == State::WAITING_RESTART) finish(child);  // its last run stands
    }
    escalate();
  }

  // Sends the next signal of SIGINT -> SIGTERM -> SIGKILL to every running process group.
  void escalate() {
    if (stage_ >= 3) return;
    const int signal_number = kStageSignals[stage_];
    ++stage_;
    for (Child& child : children_) {
      if (child.state != State::RUNNING) continue;
      signalGroup(child.pid, signal_number);
      child.stop_sent = true;
      child.report.strongest_stop_signal = signal_number;
    }
    stage_deadline_ = Clock::now() + toDuration(launch_.shutdown_timeout);
  }

  static void signalGroup(pid_t pid, int signal_number) {
    // Fall back to the pid if the child moved itself out of its process group.
    if (kill(-pid, signal_number) != 0 && errno == ESRCH) kill(pid, signal_number);
  }

  // Reaps leftovers of process groups whose leader exited (ours once we are subreaper).
  void reapOrphanGroups(bool block) {
    for (auto it = orphan_groups_.begin(); it != orphan_groups_.end();) {
      const pid_t group = *it;
      bool done = false;
      while (true) {
        int status = 0;
        const pid_t result = waitpid(-group, &status, WNOHANG);
        if (result > 0) continue;
        if (result < 0 && errno == EINTR) continue;
        if (result < 0) {  // ECHILD: no child of ours left in that group
          done = true;
          break;
        }
        // Children of ours remain in the group, so the group id is still in use.
        kill(-group, SIGKILL);
        if (!block) break;
        const pid_t waited = waitpid(-group, &status, 0);
        if (waited < 0 && errno != EINTR) {
          done = true;
          break;
        }
      }
      it = done ? orphan_groups_.erase(it) : std::next(it);
    }
  }

  LaunchReport report() {
    LaunchReport launch_report;
    launch_report.end = end_;
    const bool any_required = std::any_of(children_.begin(), children_.end(),
                                          [](const Child& c) { return c.process->required; });
    const Child* first_failure = nullptr;
    for (const Child& child : children_) {
      launch_report.processes.push_back(child.report);
      if (any_required && !child.process->required) continue;
      if (child.report.succeeded()) continue;
      if (first_failure == nullptr || child.finish_order < first_failure->finish_order) {
        first_failure = &child;
      }
    }
    if (first_failure != nullptr) {
      const ProcessReport& failed = first_failure->report;
      switch (failed.outcome) {
        case ProcessOutcome::EXITED:
          launch_report.exit_code = failed.exit_code;
          break;
        case ProcessOutcome::SIGNALED:
          launch_report.exit_code = 128 + failed.signal;
          break;
        case ProcessOutcome::START_FAILED:
          launch_report.exit_code = kStartFailedExitCode;
          break;
      }
      if (launch_report.exit_code == 0) launch_report.exit_code = 1;
    }
    for (const ProcessReport& process : launch_report.processes) {
      std::string name = process.name;
      name.resize(name_width_, ' ');
      log(name + "  " + process.describe() + (process.required ? " [required]" : "") +
          ", restarts: " + std::to_string(process.restarts));
    }
    std::string summary = "exit code " + std::to_string(launch_report.exit_code);
    if (first_failure != nullptr) {
      summary += " (" + first_failure->process->name + " " + first_failure->report.describe() + ")";
    }
    log(summary);
    return launch_report;
  }

  static constexpr int kStageSignals[3] = {SIGINT, SIGTERM, SIGKILL};

  const LaunchDescription& launch_;
  const SupervisorOptions& options_;
  const int wake_fd_;
  TempDir temp_dir_;
  std::vector<Child> children_;
  std::vector<pid_t> orphan_groups_;  // groups whose leader was reaped
  size_t name_width_ = 0;
  bool shutting_down_ = false;
  int stage_ = 0;  // shutdown signals sent so far (0..3)
  Clock::time_point stage_deadline_;
  LaunchEnd end_ = LaunchEnd::ALL_EXITED;
  long next_finish_order_ = 0;
};

}  // namespace

void SupervisorOptions::check() const {
  const auto fail = [](const std::string& message) {
    throw std::invalid_argument("SupervisorOptions: " + message);
  };
  for (const auto& [name, fd] : {std::pair<const char*, int>{"stdout_fd", stdout_fd},
                                 {"stderr_fd", stderr_fd},
                                 {"log_fd", log_fd}}) {
    if (fd < 0) fail(std::string(name) + " must be >= 0, got " + std::to_string(fd));
  }
  if (!std::isfinite(poll_interval) || poll_interval <= 0.0 || poll_interval > 10.0) {
    fail("poll_interval must be in (0, 10] s, got " + std::to_string(poll_interval));
  }
}

bool ProcessReport::succeeded() const {
  return stopped || (outcome == ProcessOutcome::EXITED && exit_code == 0);
}

std::string ProcessReport::describe() const {
  std::string text;
  switch (outcome) {
    case ProcessOutcome::EXITED:
      text = "exited with code " + std::to_string(exit_code);
      break;
    case ProcessOutcome::SIGNALED:
      text = "killed by " + signalName(signal);
      break;
    case ProcessOutcome::START_FAILED:
      text = stopped ? "not started" : "failed to start: " + start_error;
      break;
  }
  if (stopped && outcome != ProcessOutcome::START_FAILED) {
    text = "stopped with " + signalName(strongest_stop_signal) + ", " + text;
  }
  return text;
}

const ProcessReport* LaunchReport::find(const std::string& name) const {
  for (const ProcessReport& process : processes) {
    if (process.name == name) return &process;
  }
  return nullptr;
}

Supervisor::Supervisor(LaunchDescription launch, SupervisorOptions options)
    : launch_(std::move(launch)), options_(std::move(options)) {
  launch_.check();
  options_.check();
  for (const ProcessDescription& process : launch_.processes) {
    // Throws early, naming the process, when the auv executable is needed but missing.
    buildProcessCommand(launch_, process, options_.auv_executable, "/");
  }
  if (pipe2(wake_pipe_, O_CLOEXEC | O_NONBLOCK) != 0) {
    throw std::runtime_error(std::string("Supervisor: pipe failed: ") + std::strerror(errno));
  }
}

Supervisor::~Supervisor() {
  closeFd(wake_pipe_[0]);
  closeFd(wake_pipe_[1]);
}

void Supervisor::requestShutdown() {
  const unsigned char byte = kShutdownRequestByte;
  [[maybe_unused]] const ssize_t written = write(wake_pipe_[1], &byte, 1);
}

LaunchReport Supervisor::run() {
  if (started_.exchange(true)) throw std::runtime_error("Supervisor::run() called twice");
  ProcessStateGuard guard(wake_pipe_[1], options_.handle_signals, options_.reap_orphans);
  Run run(launch_, options_, wake_pipe_[0]);
  return run.execute(options_.auv_executable);
}

}  // namespace auv::bringup
