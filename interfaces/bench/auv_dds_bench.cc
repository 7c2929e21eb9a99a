// auv_dds_bench: round-trip latency and throughput through our layer (Node, Publisher,
// Subscription, Executor) on either vendor. Two processes form a pair, e.g.
//   auv_dds_bench --role pong --vendor fastdds    --domain 201 --size 1k &
//   auv_dds_bench --role ping --vendor cyclonedds --domain 201 --size 1k --count 2000
// --dispatch executor (default): callbacks run on the executor thread, as in every component;
//   the pong echoes from its subscription callback, the ping waits with Executor::spinUntil.
//   Like for like with the raw programs' --dispatch thread.
// --dispatch middleware: subscriptions with CallbackThread::MIDDLEWARE; the pong echoes and the
//   ping sends its next ping from the vendor's listener thread, no executor at all. Like for
//   like with the raw programs' --dispatch listener.
// The message is auv::msg::FileChunkReply: `data` carries the payload,
// `header.sequence_number` the sequence number and `offset` the sender's send time (steady
// clock, informative only).

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <functional>
#include <iostream>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "auv/interfaces/executor.h"
#include "auv/interfaces/node.h"
#include "auv/interfaces/qos.h"
#include "auv/msg/all.h"
#include "bench_common.h"

namespace {

namespace ai = auv::interfaces;
using auv::bench::BenchOptions;
using auv::bench::Dispatch;
using auv::bench::kStopSequence;
using auv::bench::nowNs;
using auv::msg::FileChunkReply;

constexpr const char* kTool = "ours";
constexpr auto kPollPeriod = std::chrono::milliseconds(20);  // matching/stop polling period

ai::QosProfile profileOf(const BenchOptions& options) {
  return options.qos == "command" ? ai::commandQos() : ai::sensorDataQos();
}

ai::SubscriptionOptions subscriptionOptions(const BenchOptions& options) {
  ai::SubscriptionOptions o;
  o.callback_thread = options.dispatch == Dispatch::MIDDLEWARE ? ai::CallbackThread::MIDDLEWARE
                                                               : ai::CallbackThread::EXECUTOR;
  return o;
}

std::vector<std::pair<std::string, std::string>> fieldsOf(const BenchOptions& options) {
  auto fields = auv::bench::commonFields(kTool, options.vendor, options);
  fields.emplace_back("dispatch", auv::bench::toString(options.dispatch));
  return fields;
}

// Polls `done` (middleware mode has no executor to wait with); false on timeout.
bool waitFor(const std::function<bool()>& done, double timeout_s) {
  const int64_t deadline = nowNs() + static_cast<int64_t>(timeout_s * 1e9);
  while (!done()) {
    if (nowNs() > deadline) return false;
    std::this_thread::sleep_for(kPollPeriod);
  }
  return true;
}

std::chrono::nanoseconds seconds(double s) {
  return std::chrono::nanoseconds(static_cast<int64_t>(s * 1e9));
}

FileChunkReply makeMessage(uint32_t size) {
  FileChunkReply message;
  message.data().resize(size);
  for (uint32_t i = 0; i < size; ++i) message.data()[i] = static_cast<uint8_t>(i * 131u + 7u);
  return message;
}

FileChunkReply stopMarker() {
  FileChunkReply message;
  message.header().sequence_number(kStopSequence);
  return message;
}

// Reports a pair that never matched, so run_bench.sh records the failure instead of a gap.
int reportNoMatch(const BenchOptions& options) {
  auto fields = fieldsOf(options);
  fields.emplace_back("status", "no_match");
  auv::bench::printResult(fields);
  std::cerr << "auv_dds_bench: no match on domain " << options.domain << " within "
            << options.timeout_s << " s\n";
  return 1;
}

int runPing(ai::Node& node, const BenchOptions& options) {
  auv::bench::PingSession session(options);
  auto pub =
      node.createPublisher<FileChunkReply>(auv::bench::pingTopic(options), profileOf(options));
  FileChunkReply ping = makeMessage(options.size);
  auto send = [&] {
    ping.header().sequence_number(session.startPing());
    ping.offset(static_cast<uint64_t>(nowNs()));
    pub->publish(ping);
  };
  const bool middleware = options.dispatch == Dispatch::MIDDLEWARE;
  std::mutex mutex;      // middleware mode: session and ping, shared with the listener thread
  bool running = false;  // middleware mode: the listener sends the next ping once measuring
  auto sub = node.createSubscription<FileChunkReply>(
      auv::bench::pongTopic(options), profileOf(options),
      [&](const FileChunkReply& pong) {
        if (!middleware) {
          session.onPong(pong.header().sequence_number(), pong.data().size());
          return;
        }
        std::lock_guard<std::mutex> lock(mutex);
        if (session.onPong(pong.header().sequence_number(), pong.data().size()) && running &&
            !session.finished())
          send();  // next ping straight from the listener, as the raw listener mode does
      },
      subscriptionOptions(options));
  auto matched = [&] { return pub->matchedSubscriptions() > 0 && sub->matchedPublishers() > 0; };
  const int64_t deadline = nowNs() + static_cast<int64_t>(options.timeout_s * 1e9);

  if (middleware) {
    if (!waitFor(matched, options.timeout_s)) return reportNoMatch(options);
    std::condition_variable never;  // a poll period: the listener does the work
    std::unique_lock<std::mutex> lock(mutex);
    running = true;
    send();
    while (!session.finished() && nowNs() < deadline) {
      never.wait_for(lock, std::chrono::milliseconds(50));
      if (session.finished()) break;
      if (session.awaiting() && session.outstandingNs() > options.ping_timeout_s * 1e9)
        session.abandonPing();
      if (!session.awaiting()) send();
    }
    running = false;
  } else {
    ai::Executor executor;
    executor.add(node);
    if (!executor.spinUntil(matched, seconds(options.timeout_s))) return reportNoMatch(options);
    while (!session.finished() && nowNs() < deadline) {
      send();
      if (!executor.spinUntil([&session] { return !session.awaiting(); },
                              seconds(options.ping_timeout_s)))
        session.abandonPing();
    }
  }
  const FileChunkReply stop = stopMarker();
  for (int i = 0; i < 3; ++i) {  // three times: cheap insurance for best effort
    pub->publish(stop);
    std::this_thread::sleep_for(kPollPeriod);
  }
  std::lock_guard<std::mutex> lock(mutex);
  session.report(fieldsOf(options));
  return 0;
}

int runPong(ai::Node& node, const BenchOptions& options) {
  auto pub =
      node.createPublisher<FileChunkReply>(auv::bench::pongTopic(options), profileOf(options));
  std::atomic<bool> stopped{false};
  uint64_t echoed = 0;  // written by the one thread running the callback
  auto sub = node.createSubscription<FileChunkReply>(
      auv::bench::pingTopic(options), profileOf(options),
      [&](const FileChunkReply& ping) {
        if (ping.header().sequence_number() == kStopSequence) {
          stopped = true;
          return;
        }
        pub->publish(ping);
        ++echoed;
      },
      subscriptionOptions(options));
  if (options.dispatch == Dispatch::MIDDLEWARE) {
    waitFor([&stopped] { return stopped.load(); }, options.timeout_s);
  } else {
    ai::Executor executor;
    executor.add(node);
    executor.spinUntil([&stopped] { return stopped.load(); }, seconds(options.timeout_s));
  }
  sub.reset();  // no callback after this: `echoed` is final
  auto fields = fieldsOf(options);
  fields.insert(fields.end(),
                {{"status", stopped ? "ok" : "timeout"}, {"echoed", std::to_string(echoed)}});
  auv::bench::printResult(fields);
  return stopped ? 0 : 1;
}

int runPub(ai::Node& node, const BenchOptions& options) {
  auto pub =
      node.createPublisher<FileChunkReply>(auv::bench::dataTopic(options), profileOf(options));
  const int64_t match_deadline = nowNs() + static_cast<int64_t>(options.timeout_s * 1e9);
  while (pub->matchedSubscriptions() == 0 && nowNs() < match_deadline)
    std::this_thread::sleep_for(kPollPeriod);
  if (pub->matchedSubscriptions() == 0) return reportNoMatch(options);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // let the reader match us too

  auv::bench::PublishSession session(options);
  FileChunkReply message = makeMessage(options.size);
  session.start();
  while (session.running()) {
    message.header().sequence_number(session.nextSequence());
    message.offset(static_cast<uint64_t>(nowNs()));
    try {
      pub->publish(message);
    } catch (const std::runtime_error&) {
      session.onWriteFailed();  // e.g. a reliable write blocked past max_blocking_time
    }
  }
  session.report(fieldsOf(options));
  const FileChunkReply stop = stopMarker();
  for (int i = 0; i < 3; ++i) {
    try {
      pub->publish(stop);
    } catch (const std::runtime_error&) {
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // let repairs finish
  return 0;
}

int runSub(ai::Node& node, const BenchOptions& options) {
  auv::bench::ThroughputSink sink(options);
  std::mutex mutex;  // middleware mode: the sink is shared with the listener thread
  auto sub = node.createSubscription<FileChunkReply>(
      auv::bench::dataTopic(options), profileOf(options),
      [&](const FileChunkReply& m) {
        std::lock_guard<std::mutex> lock(mutex);
        sink.onSample(m.header().sequence_number(), m.data().size());
      },
      subscriptionOptions(options));
  const int64_t start = nowNs();
  auto finished = [&] {
    std::lock_guard<std::mutex> lock(mutex);
    return sink.finished(start);
  };
  if (options.dispatch == Dispatch::MIDDLEWARE) {
    while (!finished()) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  } else {
    ai::Executor executor;
    executor.add(node);
    while (!finished()) executor.spinOnce(std::chrono::milliseconds(100));
  }
  sub.reset();  // no callback after this
  sink.report(fieldsOf(options));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  BenchOptions options;
  try {
    options = auv::bench::parseOptions(argc, argv, "auv_dds_bench", auv::bench::Program::OURS);
  } catch (const std::invalid_argument& e) {
    std::cerr << e.what() << "\n" << auv::bench::usage("auv_dds_bench", auv::bench::Program::OURS);
    return 2;
  }
  try {
    ai::NodeOptions node_options;
    node_options.vendor = ai::vendorFromString(options.vendor);
    node_options.domain_id = options.domain;
    ai::Node node("bench_" + auv::bench::toString(options.role), node_options);
    switch (options.role) {
      case auv::bench::Role::PING:
        return runPing(node, options);
      case auv::bench::Role::PONG:
        return runPong(node, options);
      case auv::bench::Role::PUB:
        return runPub(node, options);
      case auv::bench::Role::SUB:
        return runSub(node, options);
    }
  } catch (const std::exception& e) {
    std::cerr << "auv_dds_bench: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
