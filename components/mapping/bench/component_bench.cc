#include "component_bench.h"

#include <pthread.h>
#include <sched.h>
#include <signal.h>
#include <spawn.h>
#include <sys/mman.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <fstream>
#include <functional>
#include <mutex>
#include <sstream>
#include <thread>

#include "auv/interfaces/executor.h"
#include "auv/interfaces/msg_time.h"
#include "auv/mapping/components/mapping_component.h"

extern char** environ;

namespace auv::mapping::bench {
namespace {

using namespace std::chrono_literals;
using interfaces::Node;
using interfaces::nodeOptions;
using SteadyClock = std::chrono::steady_clock;

int64_t steadyNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(SteadyClock::now().time_since_epoch())
      .count();
}

double cpuSeconds(clockid_t clock) {
  timespec t{};
  clock_gettime(clock, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// utime + stime of /proc/<pid>[/task/<tid>]/stat, in seconds (clock-tick resolution).
double procCpuSeconds(const std::string& stat_path) {
  std::ifstream file(stat_path);
  std::string line;
  std::getline(file, line);
  const auto paren = line.rfind(')');
  if (paren == std::string::npos) return 0.0;
  std::istringstream fields(line.substr(paren + 2));
  std::string field;
  double ticks = 0.0;
  for (int i = 3; i <= 15 && fields >> field; ++i) {  // field 3 is the state
    if (i == 14 || i == 15) ticks += std::stod(field);
  }
  return ticks / static_cast<double>(sysconf(_SC_CLK_TCK));
}

std::vector<std::string> qosOverrides(const ComponentRun& run) {
  if (run.qos.empty()) return {};
  return {"qos.nav/odometry:=" + run.qos, "qos.sonar/beam:=" + run.qos,
          "qos.sonar/scan:=" + run.qos};
}

std::vector<std::string> componentParameters(const ComponentRun& run) {
  std::vector<std::string> parameters = qosOverrides(run);
  parameters.insert(parameters.end(), run.parameters.begin(), run.parameters.end());
  return parameters;
}

/// How far the component is, written by the thread that spins it after each batch of
/// callbacks (in this process, or in the child through a shared memfd page).
struct Progress {
  std::atomic<uint64_t> beams{0};   ///< inserted + dropped
  std::atomic<uint64_t> clouds{0};  ///< inserted + dropped
  void update(const MappingComponent& mapping) {
    beams.store(mapping.beamsInserted() + mapping.beamsDropped(), std::memory_order_relaxed);
    clouds.store(mapping.cloudsInserted() + mapping.cloudsDropped(), std::memory_order_relaxed);
  }
};
static_assert(std::atomic<uint64_t>::is_always_lock_free, "shared between processes");

/// A Progress in memory a child process can map (ChildProcess hands it the fd).
class SharedProgress {
 public:
  SharedProgress() : fd_(memfd_create("mapping_bench_progress", 0)) {
    if (fd_ < 0 || ftruncate(fd_, sizeof(Progress)) != 0)
      throw std::runtime_error("memfd_create failed");
    progress_ = map(fd_);
  }
  ~SharedProgress() {
    munmap(progress_, sizeof(Progress));
    close(fd_);
  }
  static Progress* map(int fd) {
    void* memory = mmap(nullptr, sizeof(Progress), PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
    if (memory == MAP_FAILED) throw std::runtime_error("cannot map the progress page");
    return new (memory) Progress;  // zero-filled page; the placement new only types it
  }
  int fd() const { return fd_; }
  Progress& progress() { return *progress_; }

 private:
  int fd_;
  Progress* progress_ = nullptr;
};

/// The feeder's side: publishers of the three inputs and a thread that sends the stream, at
/// most `window` beams (or clouds) ahead of what the component has taken. Keep-all readers
/// hold 256 samples (bulk_transfer); beyond that they reject samples, which the writer only
/// repeats after a heartbeat: stalls that would measure DDS repair timing, not mapping.
class Feeder {
 public:
  Feeder(Node& node, const Progress& progress, std::size_t window)
      : progress_(progress),
        window_(window),
        odometry_(node.createPublisher<msg::Odometry>("nav/odometry", interfaces::stateQos())),
        beams_(node.createPublisher<msg::SonarBeam>("sonar/beam", interfaces::sensorDataQos())),
        clouds_(node.createPublisher<msg::PointCloud>("sonar/scan", interfaces::sensorDataQos())) {}
  ~Feeder() {
    try {
      stop();
    } catch (...) {  // already reported by whoever stopped it first, or moot
    }
  }

  bool matched() const {
    return odometry_->matchedSubscriptions() > 0 && beams_->matchedSubscriptions() > 0 &&
           clouds_->matchedSubscriptions() > 0;
  }
  void startBeams(const Stream& stream) {
    thread_ = std::thread([this, &stream] {
      run([&] {
        for (const Event& event : stream.events) {
          if (stop_) return;
          if (event.kind == Event::ODOMETRY) {
            publish(*odometry_, stream.odometry[event.index]);
          } else {
            waitForWindow(progress_.beams, event.index);
            publish(*beams_, stream.beams[event.index]);
          }
        }
      });
    });
  }
  void startClouds(const Stream& stream) {
    thread_ = std::thread([this, &stream] {
      run([&] {
        for (std::size_t i = 0; i < stream.clouds.size(); ++i) {
          if (stop_) return;
          waitForWindow(progress_.clouds, i);
          publish(*clouds_, stream.clouds[i]);
        }
      });
    });
  }
  /// Joins the thread; rethrows what it threw.
  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
  }
  int retries() const { return retries_; }

 private:
  void waitForWindow(const std::atomic<uint64_t>& taken, std::size_t sent) {
    while (!stop_ && sent >= taken.load(std::memory_order_relaxed) + window_) {
      // Sleep, not spin: 2 cores are shared. 100 us = a few beams at full speed, far below the
      // window: the component only waits for it when its progress comes in big batches.
      std::this_thread::sleep_for(std::chrono::microseconds(100));
    }
  }
  void run(const std::function<void()>& body) {
    try {
      body();
    } catch (...) {
      error_ = std::current_exception();
    }
  }
  template <class T>
  void publish(interfaces::Publisher<T>& publisher, const T& message) {
    // A reliable keep-all write fails when the writer's history stays full of samples not yet
    // acknowledged for max_blocking_time (1 s): counted and written again. (Before the layer
    // retried Fast DDS 2.9's early TIMEOUT itself, this counted ~800 per 200 000 beams.)
    for (;;) {
      try {
        publisher.publish(message);
        return;
      } catch (const std::exception&) {
        if (stop_) throw;
        ++retries_;
        std::this_thread::sleep_for(std::chrono::microseconds(200));
      }
    }
  }

  const Progress& progress_;
  std::size_t window_;
  std::shared_ptr<interfaces::Publisher<msg::Odometry>> odometry_;
  std::shared_ptr<interfaces::Publisher<msg::SonarBeam>> beams_;
  std::shared_ptr<interfaces::Publisher<msg::PointCloud>> clouds_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<int> retries_{0};
  std::exception_ptr error_;
};

/// What one run sends: the stream's beams (with odometry) or its clouds.
struct Phase {
  bool beams = true;
  std::size_t sent = 0;         ///< messages the end of stream counts
  std::size_t per_message = 1;  ///< measurements per message (points per cloud)
  std::size_t window = 0;       ///< of the feeder
  uint64_t taken(const Progress& progress) const {
    return (beams ? progress.beams : progress.clouds).load(std::memory_order_relaxed);
  }
};

Phase makePhase(const Stream& stream, bool beams, std::size_t points_per_cloud,
                const ComponentRun& run) {
  Phase phase;
  phase.beams = beams;
  phase.sent = beams ? stream.beams.size() : stream.clouds.size();
  phase.per_message = beams ? 1 : points_per_cloud;
  phase.window = beams ? run.beam_window : run.cloud_window;
  return phase;
}

void start(Feeder& feeder, const Stream& stream, const Phase& phase) {
  if (phase.beams)
    feeder.startBeams(stream);
  else
    feeder.startClouds(stream);
}

void finish(Feeder& feeder, const Phase& phase, ComponentResult& result) {
  try {
    feeder.stop();
  } catch (const std::exception& e) {
    result.error = std::string("feeder: ") + e.what();
  }
  result.publish_retries = feeder.retries();
  result.per_s = static_cast<double>(result.sent * phase.per_message) / result.seconds;
}

std::chrono::nanoseconds timeout(const ComponentRun& run) {
  return std::chrono::nanoseconds(static_cast<int64_t>(run.timeout_s * 1e9));
}

ComponentResult runInProcess(const Stream& stream, const Phase& phase, const ComponentRun& run) {
  ComponentResult result;
  result.sent = phase.sent;
  Node mapping_node("mapping", nodeOptions(run.vendor, run.domain, componentParameters(run)));
  MappingComponent mapping;
  mapping.configure(mapping_node);
  Progress progress;
  Node feeder_node("mapping_bench", nodeOptions(run.feeder_vendor.value_or(run.vendor), run.domain,
                                                qosOverrides(run)));
  Feeder feeder(feeder_node, progress, phase.window);
  interfaces::Executor executor;
  executor.add(mapping_node);
  mapping.activate();
  if (!executor.spinUntil([&] { return feeder.matched(); }, 20s)) {
    result.error = "the component's subscriptions did not match within 20 s";
    return result;
  }
  executor.spinUntil([] { return false; }, 500ms);  // discovery settles, first FULL goes out

  // Checked after every batch of callbacks: exact, and it feeds the feeder's window.
  auto done = [&] {
    progress.update(mapping);
    return phase.taken(progress) >= phase.sent;
  };
  const double thread_cpu0 = cpuSeconds(CLOCK_THREAD_CPUTIME_ID);
  const double process_cpu0 = cpuSeconds(CLOCK_PROCESS_CPUTIME_ID);
  const int64_t t0 = steadyNs();
  start(feeder, stream, phase);  // the feeder thread inherits this thread's CPU
  if (run.pin) pinThisThread(kWorkCpu);
  const bool finished = executor.spinUntil(done, timeout(run));
  if (run.pin) pinThisThread(kOtherCpu);
  result.seconds = 1e-9 * static_cast<double>(steadyNs() - t0);
  result.executor_cpu_s = cpuSeconds(CLOCK_THREAD_CPUTIME_ID) - thread_cpu0;
  result.total_cpu_s = cpuSeconds(CLOCK_PROCESS_CPUTIME_ID) - process_cpu0;
  finish(feeder, phase, result);
  result.dropped = phase.beams ? mapping.beamsDropped() : mapping.cloudsDropped();
  result.map_ot = mapping.builder().fullWithProbabilities();
  mapping.deactivate();
  mapping.cleanup();
  if (!finished && result.error.empty()) {
    result.error = "timed out: " + std::to_string(phase.taken(progress)) + " of " +
                   std::to_string(phase.sent) + " taken";
  }
  result.ok = result.error.empty();
  return result;
}

/// map/update as the planner would read it, recorded from the vendor's thread.
class UpdateLog {
 public:
  void onUpdate(const msg::OctomapUpdate& update) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++count_;
    newest_sequence_ = std::max<uint64_t>(newest_sequence_, update.sequence_number());
    if (update.kind() == msg::OCTOMAP_UPDATE_FULL && update.sequence_number() > keep_full_after_) {
      last_full_.assign(update.data().begin(), update.data().end());
      has_full_ = true;
    }
    changed_.notify_all();
  }
  /// Waits for a FULL with a sequence number above `after` (0: any); returns its data or "".
  std::string waitForFull(uint64_t after, std::chrono::nanoseconds timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (keep_full_after_ != after) {
      keep_full_after_ = after;
      has_full_ = false;
    }
    if (!changed_.wait_for(lock, timeout, [&] { return has_full_; })) return "";
    return last_full_;
  }
  int count() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return count_;
  }
  uint64_t newestSequence() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return newest_sequence_;
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  int count_ = 0;
  uint64_t newest_sequence_ = 0;
  uint64_t keep_full_after_ = 0;
  bool has_full_ = false;
  std::string last_full_;
};

class ChildProcess {
 public:
  /// Starts `executable` with `args`; the child gets `shared_fd` as fd 3 and no other
  /// descriptor beyond 0-2 (none of this process's DDS sockets).
  ChildProcess(const std::string& executable, const std::vector<std::string>& args, int shared_fd) {
    std::vector<char*> argv;
    std::vector<std::string> all{executable};
    all.insert(all.end(), args.begin(), args.end());
    for (auto& a : all) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, shared_fd, kChildSharedFd);
    posix_spawn_file_actions_addclosefrom_np(&actions, kChildSharedFd + 1);
    const int error =
        posix_spawn(&pid_, executable.c_str(), &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (error != 0) throw std::runtime_error("cannot start " + executable);
  }
  static constexpr int kChildSharedFd = 3;
  ~ChildProcess() { stop(); }
  bool running() { return pid_ > 0 && waitpid(pid_, nullptr, WNOHANG) == 0; }
  double cpuSeconds() const { return procCpuSeconds(proc() + "/stat"); }
  /// The main thread spins the executor.
  double mainThreadCpuSeconds() const {
    return procCpuSeconds(proc() + "/task/" + std::to_string(pid_) + "/stat");
  }
  /// SIGTERM (the host deactivates and cleans up), SIGKILL after 10 s.
  void stop() {
    if (pid_ <= 0) return;
    kill(pid_, SIGTERM);
    for (int i = 0; i < 1000; ++i) {
      if (waitpid(pid_, nullptr, WNOHANG) == pid_) {
        pid_ = 0;
        return;
      }
      std::this_thread::sleep_for(10ms);
    }
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
    pid_ = 0;
  }

 private:
  std::string proc() const { return "/proc/" + std::to_string(pid_); }
  pid_t pid_ = 0;
};

ComponentResult runInChild(const Stream& stream, const Phase& phase, const ComponentRun& run) {
  ComponentResult result;
  result.sent = phase.sent;
  SharedProgress shared;
  const Progress& progress = shared.progress();
  std::vector<std::string> args{"--serve",
                                "--vendor",
                                interfaces::toString(run.vendor),
                                "--domain",
                                std::to_string(run.domain),
                                "--progress-fd",
                                std::to_string(ChildProcess::kChildSharedFd)};
  args.push_back(run.pin ? "--pin" : "--no-pin");
  for (const std::string& p : componentParameters(run)) {
    args.push_back("-p");
    args.push_back(p);
  }
  ChildProcess child(run.self_executable, args, shared.fd());
  Node bench_node("mapping_bench", nodeOptions(run.feeder_vendor.value_or(run.vendor), run.domain,
                                               qosOverrides(run)));
  Feeder feeder(bench_node, progress, phase.window);
  UpdateLog log;
  // In the vendor's thread: nothing spins this node.
  interfaces::SubscriptionOptions in_middleware;
  in_middleware.callback_thread = interfaces::CallbackThread::MIDDLEWARE;
  auto updates = bench_node.createSubscription<msg::OctomapUpdate>(
      "map/update", interfaces::mapQos(),
      std::function<void(const msg::OctomapUpdate&)>(
          [&log](const msg::OctomapUpdate& u) { log.onUpdate(u); }),
      in_middleware);
  auto request_full =
      bench_node.createClient<msg::TriggerRequest, msg::TriggerReply>("map/request_full");

  const auto deadline = SteadyClock::now() + 30s;
  while (!feeder.matched() && SteadyClock::now() < deadline) std::this_thread::sleep_for(10ms);
  if (!feeder.matched() || log.waitForFull(0, 30s).empty()) {
    result.error = "the component process did not come up within 30 s";
    return result;
  }
  // The FULL for a new reader stays the newest sample for late_joiner_hold (2 s): start after.
  std::this_thread::sleep_for(2500ms);

  const int updates_before = log.count();
  const double process_cpu0 = child.cpuSeconds() + cpuSeconds(CLOCK_PROCESS_CPUTIME_ID);
  const double thread_cpu0 = child.mainThreadCpuSeconds();
  const int64_t t0 = steadyNs();
  start(feeder, stream, phase);
  const auto end = SteadyClock::now() + timeout(run);
  while (phase.taken(progress) < phase.sent && SteadyClock::now() < end && child.running()) {
    std::this_thread::sleep_for(1ms);  // end of stream to 1 ms; seconds are measured
  }
  result.seconds = 1e-9 * static_cast<double>(steadyNs() - t0);
  result.executor_cpu_s = child.mainThreadCpuSeconds() - thread_cpu0;
  result.total_cpu_s = child.cpuSeconds() + cpuSeconds(CLOCK_PROCESS_CPUTIME_ID) - process_cpu0;
  finish(feeder, phase, result);
  if (phase.taken(progress) < phase.sent) {
    result.error = "stopped at " + std::to_string(phase.taken(progress)) + " of " +
                   std::to_string(phase.sent) + " taken";
    return result;
  }
  result.updates = log.count() - updates_before;

  // The final map, as a FULL the reader asks for (the counters cover drops: none expected).
  const uint64_t newest = log.newestSequence();
  msg::TriggerReply reply;
  if (request_full->call(msg::TriggerRequest(), &reply, 10s) == interfaces::CallStatus::OK)
    result.map_ot = log.waitForFull(newest, 10s);
  if (result.map_ot.empty() && result.error.empty())
    result.error = "no FULL map after map/request_full";
  child.stop();
  result.ok = result.error.empty();
  return result;
}

ComponentResult runPhase(const Stream& stream, const Phase& phase, const ComponentRun& run) {
  try {
    return run.child_process ? runInChild(stream, phase, run) : runInProcess(stream, phase, run);
  } catch (const std::exception& e) {
    ComponentResult result;
    result.error = e.what();
    return result;
  }
}

}  // namespace

ComponentResult runBeams(const Stream& stream, const ComponentRun& run) {
  return runPhase(stream, makePhase(stream, true, 1, run), run);
}

ComponentResult runClouds(const Stream& stream, std::size_t points_per_cloud,
                          const ComponentRun& run) {
  return runPhase(stream, makePhase(stream, false, points_per_cloud, run), run);
}

bool pinThisThread(int cpu) {
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  return pthread_setaffinity_np(pthread_self(), sizeof(set), &set) == 0;
}

int serveComponent(interfaces::Vendor vendor, int domain,
                   const std::vector<std::string>& parameters, int progress_fd, bool pin) {
  // What interfaces::runComponents does for `auv run mapping`, plus the progress page.
  Progress* progress = SharedProgress::map(progress_fd);
  if (pin) pinThisThread(kOtherCpu);  // the DDS threads created below inherit it
  interfaces::Executor::installSignalHandlers();
  Node node("mapping", nodeOptions(vendor, domain, parameters));
  MappingComponent mapping;
  mapping.configure(node);
  interfaces::Executor executor;
  executor.add(node);
  mapping.activate();
  if (pin) pinThisThread(kWorkCpu);
  while (!executor.isShutdown()) {  // Executor::spin(), publishing progress after each batch
    executor.spinOnce(100ms);
    progress->update(mapping);
  }
  mapping.deactivate();
  mapping.cleanup();
  executor.remove(node);
  return 0;
}

}  // namespace auv::mapping::bench
