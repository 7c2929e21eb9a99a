#pragma once
// Shared parts of the middleware benchmark programs (auv_dds_bench, raw_fastdds_bench,
// raw_cyclonedds_bench): command-line options, the ping-pong and throughput bookkeeping and
// the one-line results that run_bench.sh parses. Vendor-neutral: the programs only pass
// sequence numbers and payload sizes in, so the same code measures our layer and the raw
// vendor APIs. Nothing here is thread-safe; callers that touch a session from a middleware
// thread and the main thread guard it with their own mutex.

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace auv::bench {

/// What one process does in a benchmark pair.
enum class Role {
  PING,  ///< Sends a ping, waits for its echo, records the round trip; repeats.
  PONG,  ///< Echoes every ping back until the stop marker arrives.
  PUB,   ///< Publishes as fast as possible for a fixed time, then the stop marker.
  SUB,   ///< Counts what arrives and reports the steady-state rate.
};

/// Where arrivals are handled. Raw programs: LISTENER or THREAD; ours: EXECUTOR or
/// MIDDLEWARE (the subscription's CallbackThread). Like for like: THREAD ~ EXECUTOR (a
/// listener wakes another thread), LISTENER ~ MIDDLEWARE (answered in the vendor's thread).
enum class Dispatch {
  LISTENER,    ///< Raw: take and answer inside the vendor's listener (ddsperf's default).
  THREAD,      ///< Raw: listener only wakes an application thread that takes and answers.
  EXECUTOR,    ///< Ours: callbacks on the executor thread (the layer's default).
  MIDDLEWARE,  ///< Ours: CallbackThread::MIDDLEWARE, callbacks in the vendor's listener.
};

/// Which program parses the options: decides the flags and dispatch modes accepted.
enum class Program {
  OURS,  ///< auv_dds_bench: --vendor, --dispatch executor|middleware.
  RAW,   ///< raw_*_bench: --dispatch listener|thread.
};

/// Sequence number of the stop marker: tells the pong/sub to report and exit.
constexpr uint64_t kStopSequence = UINT64_MAX;

/// Longest ping warm-up, s: slow pairs (4 MiB across vendors) start measuring anyway.
constexpr double kMaxWarmupS = 1.0;

/// Command-line options common to all three programs. Defaults are the short run.
struct BenchOptions {
  Role role = Role::PING;
  std::string vendor = "cyclonedds";       ///< auv_dds_bench only: cyclonedds | fastdds.
  std::string qos = "command";             ///< command (reliable) | sensor_data (best effort).
  Dispatch dispatch = Dispatch::LISTENER;  ///< Raw default LISTENER, ours default EXECUTOR.
  uint32_t size = 1024;                    ///< Bytes in the message's `data` sequence.
  int count = 1000;                        ///< Ping: measured round trips.
  int warmup = 100;             ///< Ping: unmeasured round trips first (at most kMaxWarmupS).
  double duration_s = 3.0;      ///< Pub: seconds of publishing; ping: cap on measuring.
  double sub_warmup_s = 0.5;    ///< Sub: seconds after the first sample not counted.
  double timeout_s = 30.0;      ///< Matching deadline, and pong/sub overall deadline, s.
  double ping_timeout_s = 2.0;  ///< Ping: a round trip slower than this is lost, s.
  double idle_timeout_s = 2.0;  ///< Sub: ends this long after the last sample, s.
  int domain = 200;             ///< DDS domain id, 0..232.
  std::string topic = "bench";  ///< Topic prefix: <topic>/ping, <topic>/pong, <topic>/data.

  /// Throws std::invalid_argument naming the field and value when an option is out of range.
  void check() const;
};

/// Parses `--role ping --size 1024 ...`; throws std::invalid_argument naming the flag.
/// `name` only shapes the help text; `program` decides which flags are allowed.
BenchOptions parseOptions(int argc, char** argv, const std::string& name, Program program);

/// Usage text for the program `name`.
std::string usage(const std::string& name, Program program);

std::string toString(Role role);
std::string toString(Dispatch dispatch);

/// Steady-clock nanoseconds (monotonic; used for every interval measured here).
int64_t nowNs();

/// Round-trip statistics in microseconds.
struct LatencySummary {
  size_t count = 0;
  double min_us = 0, mean_us = 0, median_us = 0, p90_us = 0, p99_us = 0, max_us = 0;
};

/// Summarises round-trip times (ns); percentiles by nearest rank.
LatencySummary summarize(std::vector<int64_t> samples_ns);

/// Prints one machine-readable line, `RESULT key=value ...`, to stdout and flushes.
void printResult(const std::vector<std::pair<std::string, std::string>>& fields);

/// Fixed-point text for result fields.
std::string fmt(double value, int decimals = 3);

/// Ping side of a ping-pong run: hands out sequence numbers, matches echoes to the
/// outstanding ping and keeps the measured round trips.
class PingSession {
 public:
  explicit PingSession(const BenchOptions& options);

  /// Sequence number of the next ping; stamps its send time. Call just before writing it.
  uint64_t startPing();
  /// Records an echo; returns true when it answers the outstanding ping (then a new ping
  /// may start). Echoes of abandoned pings and wrong sizes are counted, not timed.
  bool onPong(uint64_t sequence, size_t data_size);
  /// Gives up on the outstanding ping (lost, or slower than ping_timeout_s).
  void abandonPing();
  /// True while a ping is outstanding.
  bool awaiting() const { return awaiting_; }
  /// Nanoseconds since the outstanding ping was sent.
  int64_t outstandingNs() const { return nowNs() - sent_ns_; }
  /// True once `count` round trips were measured or `duration_s` of measuring elapsed.
  bool finished() const;
  /// Number of echoes received so far (warm-up included).
  uint64_t replies() const { return replies_; }
  /// Prints the RESULT line; `fields` come first (tool, vendor, ...).
  void report(std::vector<std::pair<std::string, std::string>> fields) const;

 private:
  BenchOptions options_;
  uint64_t next_sequence_ = 1;
  uint64_t outstanding_ = 0;  // sequence of the ping in flight
  bool awaiting_ = false;
  int64_t sent_ns_ = 0;
  int64_t first_ping_ns_ = 0;
  int64_t measure_start_ns_ = 0;  // 0 until the warm-up is over
  int64_t measure_end_ns_ = 0;
  uint64_t replies_ = 0;
  uint64_t lost_ = 0;
  uint64_t stale_ = 0;     // echoes of abandoned pings
  uint64_t bad_size_ = 0;  // echoes whose payload had the wrong length
  std::vector<int64_t> rtt_ns_;
};

/// Receiving side of a throughput run: counts samples and bytes in a steady-state window
/// (from the first sample after `sub_warmup_s` to the last data sample) and sequence gaps.
class ThroughputSink {
 public:
  explicit ThroughputSink(const BenchOptions& options);

  /// Records one sample (the stop marker ends the run).
  void onSample(uint64_t sequence, size_t data_size);
  /// True once the stop marker arrived.
  bool stopped() const { return stopped_; }
  /// True once the run is over: stopped, idle for idle_timeout_s after data, or past timeout_s.
  bool finished(int64_t start_ns) const;
  /// Prints the RESULT line; `fields` come first.
  void report(std::vector<std::pair<std::string, std::string>> fields) const;

 private:
  BenchOptions options_;
  bool stopped_ = false;
  int64_t first_ns_ = 0;         // arrival of the first data sample
  int64_t window_start_ns_ = 0;  // arrival of the first counted sample
  int64_t last_ns_ = 0;          // arrival of the last data sample
  uint64_t total_ = 0;           // data samples received, warm-up included
  uint64_t counted_ = 0;         // data samples in the window (after the first one)
  uint64_t counted_bytes_ = 0;
  uint64_t first_seq_ = 0;  // sequence number opening the window
  uint64_t max_seq_ = 0;
  uint64_t bad_size_ = 0;
};

/// Publishing side of a throughput run: the caller writes while `running()`.
class PublishSession {
 public:
  explicit PublishSession(const BenchOptions& options);
  /// Starts the clock.
  void start();
  /// True until duration_s has elapsed since start().
  bool running() const;
  /// Sequence number for the next sample.
  uint64_t nextSequence() { return ++sent_; }
  /// Counts a write that failed (timeout, resources).
  void onWriteFailed() { ++failed_; }
  /// Prints the RESULT line; `fields` come first.
  void report(std::vector<std::pair<std::string, std::string>> fields) const;

 private:
  BenchOptions options_;
  int64_t start_ns_ = 0;
  uint64_t sent_ = 0;
  uint64_t failed_ = 0;
};

/// Fields every RESULT line starts with: role, qos, size and domain of `options`.
std::vector<std::pair<std::string, std::string>> commonFields(const std::string& tool,
                                                              const std::string& vendor,
                                                              const BenchOptions& options);

/// Topic names used by every program, e.g. "bench/ping".
std::string pingTopic(const BenchOptions& options);
std::string pongTopic(const BenchOptions& options);
std::string dataTopic(const BenchOptions& options);

}  // namespace auv::bench
