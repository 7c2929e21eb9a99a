#include "bench_common.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <numeric>
#include <sstream>
#include <stdexcept>

namespace auv::bench {
namespace {

[[noreturn]] void bad(const std::string& field, const std::string& value, const std::string& why) {
  throw std::invalid_argument("bench: " + field + " = '" + value + "' " + why);
}

// "1024", "16k", "4M", "4MiB" -> bytes (binary multiples).
uint64_t parseSize(const std::string& flag, const std::string& text) {
  size_t pos = 0;
  unsigned long long value = 0;
  try {
    value = std::stoull(text, &pos);
  } catch (const std::exception&) {
    bad(flag, text, "is not a size (e.g. 64, 16k, 4M)");
  }
  const std::string suffix = text.substr(pos);
  uint64_t scale = 1;
  if (suffix.empty() || suffix == "B")
    scale = 1;
  else if (suffix == "k" || suffix == "K" || suffix == "KiB")
    scale = 1024;
  else if (suffix == "M" || suffix == "MiB")
    scale = 1024 * 1024;
  else
    bad(flag, text, "has an unknown unit (use k/KiB or M/MiB)");
  return value * scale;
}

double parseDouble(const std::string& flag, const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0') bad(flag, text, "is not a number");
  return v;
}

int parseInt(const std::string& flag, const std::string& text) {
  char* end = nullptr;
  const long v = std::strtol(text.c_str(), &end, 10);
  if (end == text.c_str() || *end != '\0') bad(flag, text, "is not an integer");
  return static_cast<int>(v);
}

double percentile(const std::vector<int64_t>& sorted, double p) {
  if (sorted.empty()) return 0;
  // Nearest rank: the smallest value with at least p of the samples at or below it.
  const size_t rank = static_cast<size_t>(std::ceil(p * static_cast<double>(sorted.size())));
  return static_cast<double>(sorted[std::min(sorted.size(), std::max<size_t>(rank, 1)) - 1]);
}

}  // namespace

void BenchOptions::check() const {
  if (vendor != "cyclonedds" && vendor != "fastdds")
    bad("--vendor", vendor, "must be cyclonedds or fastdds");
  if (qos != "command" && qos != "sensor_data") bad("--qos", qos, "must be command or sensor_data");
  if (size > 64u * 1024 * 1024) bad("--size", std::to_string(size), "must be <= 64 MiB");
  if (count < 1) bad("--count", std::to_string(count), "must be >= 1");
  if (warmup < 0) bad("--warmup", std::to_string(warmup), "must be >= 0");
  if (!(duration_s > 0)) bad("--duration", fmt(duration_s), "must be > 0 s");
  if (sub_warmup_s < 0) bad("--sub-warmup", fmt(sub_warmup_s), "must be >= 0 s");
  if (!(timeout_s > 0)) bad("--timeout", fmt(timeout_s), "must be > 0 s");
  if (!(ping_timeout_s > 0)) bad("--ping-timeout", fmt(ping_timeout_s), "must be > 0 s");
  if (!(idle_timeout_s > 0)) bad("--idle-timeout", fmt(idle_timeout_s), "must be > 0 s");
  if (domain < 0 || domain > 232) bad("--domain", std::to_string(domain), "must be in [0, 232]");
  if (topic.empty()) bad("--topic", topic, "must not be empty");
}

std::string toString(Role role) {
  switch (role) {
    case Role::PING:
      return "ping";
    case Role::PONG:
      return "pong";
    case Role::PUB:
      return "pub";
    case Role::SUB:
      return "sub";
  }
  return "?";
}

std::string toString(Dispatch dispatch) {
  switch (dispatch) {
    case Dispatch::LISTENER:
      return "listener";
    case Dispatch::THREAD:
      return "thread";
    case Dispatch::EXECUTOR:
      return "executor";
    case Dispatch::MIDDLEWARE:
      return "middleware";
  }
  return "?";
}

std::string usage(const std::string& name, Program program) {
  std::ostringstream out;
  out << "usage: " << name << " --role ping|pong|pub|sub [options]\n"
      << "  Pairs: run `pong` (or `sub`) and `ping` (or `pub`) in two processes on one domain.\n";
  if (program == Program::OURS)
    out << "  --vendor cyclonedds|fastdds  DDS vendor of this process (cyclonedds)\n"
        << "  --dispatch executor|middleware  callbacks on the executor thread, or in the\n"
        << "                               vendor's listener thread (executor)\n";
  else
    out << "  --dispatch listener|thread   answer in the vendor listener, or wake an\n"
        << "                               application thread that takes (listener)\n";
  out << "  --qos command|sensor_data    QoS profile: reliable keep-last 10, or best effort\n"
      << "                               keep-last 5 (command)\n"
      << "  --size N                     bytes of payload, suffix k/M allowed (1024)\n"
      << "  --count N                    ping: measured round trips (1000)\n"
      << "  --warmup N                   ping: unmeasured round trips first (100)\n"
      << "  --duration S                 pub: seconds publishing; ping: measuring cap (3)\n"
      << "  --sub-warmup S               sub: seconds after the first sample not counted (0.5)\n"
      << "  --timeout S                  matching deadline and pong/sub lifetime cap (30)\n"
      << "  --ping-timeout S             ping: round trip counted lost after S (2)\n"
      << "  --idle-timeout S             sub: stop S after the last sample (2)\n"
      << "  --domain D                   DDS domain id (200)\n"
      << "  --topic PREFIX               topics PREFIX/ping, PREFIX/pong, PREFIX/data (bench)\n"
      << "Prints one line `RESULT key=value ...` on stdout; progress goes to stderr.\n";
  return out.str();
}

BenchOptions parseOptions(int argc, char** argv, const std::string& name, Program program) {
  BenchOptions o;
  const bool ours = program == Program::OURS;
  o.dispatch = ours ? Dispatch::EXECUTOR : Dispatch::LISTENER;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "-h" || flag == "--help") {
      std::cout << usage(name, program);
      std::exit(0);
    }
    if (i + 1 >= argc) bad(flag, "", "needs a value (see --help)");
    const std::string value = argv[++i];
    if (flag == "--role") {
      if (value == "ping")
        o.role = Role::PING;
      else if (value == "pong")
        o.role = Role::PONG;
      else if (value == "pub")
        o.role = Role::PUB;
      else if (value == "sub")
        o.role = Role::SUB;
      else
        bad(flag, value, "must be ping, pong, pub or sub");
    } else if (flag == "--vendor" && ours) {
      o.vendor = value;
    } else if (flag == "--dispatch" && ours) {
      if (value == "executor")
        o.dispatch = Dispatch::EXECUTOR;
      else if (value == "middleware")
        o.dispatch = Dispatch::MIDDLEWARE;
      else
        bad(flag, value, "must be executor or middleware");
    } else if (flag == "--dispatch") {
      if (value == "listener")
        o.dispatch = Dispatch::LISTENER;
      else if (value == "thread")
        o.dispatch = Dispatch::THREAD;
      else
        bad(flag, value, "must be listener or thread");
    } else if (flag == "--qos") {
      o.qos = value;
    } else if (flag == "--size") {
      const uint64_t size = parseSize(flag, value);
      if (size > UINT32_MAX) bad(flag, value, "is too large");
      o.size = static_cast<uint32_t>(size);
    } else if (flag == "--count") {
      o.count = parseInt(flag, value);
    } else if (flag == "--warmup") {
      o.warmup = parseInt(flag, value);
    } else if (flag == "--duration") {
      o.duration_s = parseDouble(flag, value);
    } else if (flag == "--sub-warmup") {
      o.sub_warmup_s = parseDouble(flag, value);
    } else if (flag == "--timeout") {
      o.timeout_s = parseDouble(flag, value);
    } else if (flag == "--ping-timeout") {
      o.ping_timeout_s = parseDouble(flag, value);
    } else if (flag == "--idle-timeout") {
      o.idle_timeout_s = parseDouble(flag, value);
    } else if (flag == "--domain") {
      o.domain = parseInt(flag, value);
    } else if (flag == "--topic") {
      o.topic = value;
    } else {
      bad("option", flag, "is unknown (see --help)");
    }
  }
  o.check();
  return o;
}

int64_t nowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

LatencySummary summarize(std::vector<int64_t> samples_ns) {
  LatencySummary s;
  s.count = samples_ns.size();
  if (samples_ns.empty()) return s;
  std::sort(samples_ns.begin(), samples_ns.end());
  const double sum = std::accumulate(samples_ns.begin(), samples_ns.end(), 0.0);
  s.min_us = samples_ns.front() / 1e3;
  s.max_us = samples_ns.back() / 1e3;
  s.mean_us = sum / static_cast<double>(samples_ns.size()) / 1e3;
  s.median_us = percentile(samples_ns, 0.5) / 1e3;
  s.p90_us = percentile(samples_ns, 0.9) / 1e3;
  s.p99_us = percentile(samples_ns, 0.99) / 1e3;
  return s;
}

std::string fmt(double value, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", decimals, value);
  return buf;
}

void printResult(const std::vector<std::pair<std::string, std::string>>& fields) {
  std::ostringstream out;
  out << "RESULT";
  for (const auto& [key, value] : fields) out << ' ' << key << '=' << value;
  std::cout << out.str() << std::endl;
}

std::vector<std::pair<std::string, std::string>> commonFields(const std::string& tool,
                                                              const std::string& vendor,
                                                              const BenchOptions& options) {
  return {{"tool", tool},
          {"vendor", vendor},
          {"role", toString(options.role)},
          {"qos", options.qos},
          {"size", std::to_string(options.size)},
          {"domain", std::to_string(options.domain)}};
}

std::string pingTopic(const BenchOptions& options) { return options.topic + "/ping"; }
std::string pongTopic(const BenchOptions& options) { return options.topic + "/pong"; }
std::string dataTopic(const BenchOptions& options) { return options.topic + "/data"; }

// ---------------------------------------------------------------------------------------
// PingSession

PingSession::PingSession(const BenchOptions& options) : options_(options) {
  rtt_ns_.reserve(static_cast<size_t>(options.count));
  if (options_.warmup == 0) measure_start_ns_ = nowNs();
}

uint64_t PingSession::startPing() {
  outstanding_ = next_sequence_++;
  awaiting_ = true;
  sent_ns_ = nowNs();
  if (first_ping_ns_ == 0) first_ping_ns_ = sent_ns_;
  if (measure_start_ns_ == 0 && sent_ns_ - first_ping_ns_ > kMaxWarmupS * 1e9)
    measure_start_ns_ = sent_ns_;
  return outstanding_;
}

bool PingSession::onPong(uint64_t sequence, size_t data_size) {
  const int64_t now = nowNs();
  if (!awaiting_ || sequence != outstanding_) {
    ++stale_;
    return false;
  }
  awaiting_ = false;
  ++replies_;
  if (data_size != options_.size) {
    ++bad_size_;
    return true;
  }
  if (measure_start_ns_ == 0) {
    if (replies_ >= static_cast<uint64_t>(options_.warmup)) measure_start_ns_ = now;
    return true;
  }
  rtt_ns_.push_back(now - sent_ns_);
  measure_end_ns_ = now;
  return true;
}

void PingSession::abandonPing() {
  if (!awaiting_) return;
  awaiting_ = false;
  ++lost_;
}

bool PingSession::finished() const {
  if (rtt_ns_.size() >= static_cast<size_t>(options_.count)) return true;
  return measure_start_ns_ != 0 && nowNs() - measure_start_ns_ > options_.duration_s * 1e9;
}

void PingSession::report(std::vector<std::pair<std::string, std::string>> fields) const {
  const LatencySummary s = summarize(rtt_ns_);
  const double span_s =
      measure_end_ns_ > measure_start_ns_ ? (measure_end_ns_ - measure_start_ns_) / 1e9 : 0;
  fields.insert(fields.end(), {{"status", s.count > 0 ? "ok" : "no_data"},
                               {"count", std::to_string(s.count)},
                               {"lost", std::to_string(lost_)},
                               {"stale", std::to_string(stale_)},
                               {"bad_size", std::to_string(bad_size_)},
                               {"rtt_min_us", fmt(s.min_us)},
                               {"rtt_mean_us", fmt(s.mean_us)},
                               {"rtt_median_us", fmt(s.median_us)},
                               {"rtt_p90_us", fmt(s.p90_us)},
                               {"rtt_p99_us", fmt(s.p99_us)},
                               {"rtt_max_us", fmt(s.max_us)},
                               {"oneway_median_us", fmt(s.median_us / 2)},
                               {"oneway_p90_us", fmt(s.p90_us / 2)},
                               {"roundtrips_per_s", fmt(span_s > 0 ? s.count / span_s : 0, 1)}});
  printResult(fields);
}

// ---------------------------------------------------------------------------------------
// ThroughputSink

ThroughputSink::ThroughputSink(const BenchOptions& options) : options_(options) {}

void ThroughputSink::onSample(uint64_t sequence, size_t data_size) {
  const int64_t now = nowNs();
  if (sequence == kStopSequence) {
    stopped_ = true;
    return;
  }
  ++total_;
  if (data_size != options_.size) ++bad_size_;
  if (first_ns_ == 0) first_ns_ = now;
  max_seq_ = std::max(max_seq_, sequence);
  if (window_start_ns_ == 0) {
    if (now - first_ns_ >= options_.sub_warmup_s * 1e9) {
      window_start_ns_ = now;
      first_seq_ = sequence;
      last_ns_ = now;
    }
    return;
  }
  ++counted_;
  counted_bytes_ += data_size;
  last_ns_ = now;
}

bool ThroughputSink::finished(int64_t start_ns) const {
  const int64_t now = nowNs();
  if (stopped_) return true;
  if (first_ns_ != 0 && now - std::max(first_ns_, last_ns_) > options_.idle_timeout_s * 1e9)
    return true;
  return now - start_ns > options_.timeout_s * 1e9;
}

void ThroughputSink::report(std::vector<std::pair<std::string, std::string>> fields) const {
  const double window_s = last_ns_ > window_start_ns_ ? (last_ns_ - window_start_ns_) / 1e9 : 0;
  // Samples that should have arrived in the window: sequence numbers after the opening one.
  const uint64_t expected =
      max_seq_ > first_seq_ && window_start_ns_ != 0 ? max_seq_ - first_seq_ : 0;
  const uint64_t lost = expected > counted_ ? expected - counted_ : 0;
  const double rate = window_s > 0 ? counted_ / window_s : 0;
  fields.insert(fields.end(),
                {{"status", counted_ > 0 ? "ok" : "no_data"},
                 {"received", std::to_string(total_)},
                 {"counted", std::to_string(counted_)},
                 {"lost", std::to_string(lost)},
                 {"loss_pct", fmt(expected > 0 ? 100.0 * lost / expected : 0, 2)},
                 {"bad_size", std::to_string(bad_size_)},
                 {"stopped", stopped_ ? "1" : "0"},
                 {"window_s", fmt(window_s)},
                 {"msgs_per_s", fmt(rate, 1)},
                 {"mb_per_s", fmt(window_s > 0 ? counted_bytes_ / window_s / 1e6 : 0, 2)}});
  printResult(fields);
}

// ---------------------------------------------------------------------------------------
// PublishSession

PublishSession::PublishSession(const BenchOptions& options) : options_(options) {}

void PublishSession::start() { start_ns_ = nowNs(); }

bool PublishSession::running() const { return nowNs() - start_ns_ < options_.duration_s * 1e9; }

void PublishSession::report(std::vector<std::pair<std::string, std::string>> fields) const {
  const double elapsed_s = (nowNs() - start_ns_) / 1e9;
  fields.insert(fields.end(), {{"status", sent_ > failed_ ? "ok" : "no_data"},
                               {"sent", std::to_string(sent_)},
                               {"failed", std::to_string(failed_)},
                               {"sent_per_s", fmt(elapsed_s > 0 ? sent_ / elapsed_s : 0, 1)}});
  printResult(fields);
}

}  // namespace auv::bench
