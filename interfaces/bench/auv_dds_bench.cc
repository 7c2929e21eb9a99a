// auv_dds_bench: round-trip latency and throughput through our layer (Node, Publisher,
// Subscription, Executor) on either vendor. Two processes form a pair, e.g.
//   auv_dds_bench --role pong --vendor fastdds    --domain 201 --size 1k &
//   auv_dds_bench --role ping --vendor cyclonedds --domain 201 --size 1k --count 2000
// Callbacks run on the executor thread, as in every component: the pong echoes from its
// subscription callback, the ping waits with Executor::spinUntil. The message is
// auv::msg::FileChunkReply: `data` carries the payload, `header.sequence_number` the sequence
// number and `offset` the sender's send time (steady clock, informative only).

#include <chrono>
#include <cstdint>
#include <exception>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>

#include "auv/interfaces/executor.h"
#include "auv/interfaces/node.h"
#include "auv/interfaces/qos.h"
#include "auv/msg/all.h"
#include "bench_common.h"

namespace {

namespace ai = auv::interfaces;
using auv::bench::BenchOptions;
using auv::bench::kStopSequence;
using auv::bench::nowNs;
using auv::msg::FileChunkReply;

constexpr const char* kTool = "ours";
constexpr auto kPollPeriod = std::chrono::milliseconds(20);  // matching/stop polling period

ai::QosProfile profileOf(const BenchOptions& options) {
  return options.qos == "command" ? ai::commandQos() : ai::sensorDataQos();
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
  auto fields = auv::bench::commonFields(kTool, options.vendor, options);
  fields.emplace_back("status", "no_match");
  auv::bench::printResult(fields);
  std::cerr << "auv_dds_bench: no match on domain " << options.domain << " within "
            << options.timeout_s << " s\n";
  return 1;
}

int runPing(ai::Node& node, const BenchOptions& options) {
  ai::Executor executor;
  executor.add(node);
  auv::bench::PingSession session(options);
  auto pub =
      node.createPublisher<FileChunkReply>(auv::bench::pingTopic(options), profileOf(options));
  auto sub = node.createSubscription<FileChunkReply>(
      auv::bench::pongTopic(options), profileOf(options), [&session](const FileChunkReply& pong) {
        session.onPong(pong.header().sequence_number(), pong.data().size());
      });
  if (!executor.spinUntil(
          [&] { return pub->matchedSubscriptions() > 0 && sub->matchedPublishers() > 0; },
          seconds(options.timeout_s)))
    return reportNoMatch(options);

  FileChunkReply ping = makeMessage(options.size);
  const int64_t deadline = nowNs() + static_cast<int64_t>(options.timeout_s * 1e9);
  while (!session.finished() && nowNs() < deadline) {
    ping.header().sequence_number(session.startPing());
    ping.offset(static_cast<uint64_t>(nowNs()));
    pub->publish(ping);
    if (!executor.spinUntil([&session] { return !session.awaiting(); },
                            seconds(options.ping_timeout_s)))
      session.abandonPing();
  }
  const FileChunkReply stop = stopMarker();
  for (int i = 0; i < 3; ++i) {  // three times: cheap insurance for best effort
    pub->publish(stop);
    std::this_thread::sleep_for(kPollPeriod);
  }
  session.report(auv::bench::commonFields(kTool, options.vendor, options));
  return 0;
}

int runPong(ai::Node& node, const BenchOptions& options) {
  ai::Executor executor;
  executor.add(node);
  auto pub =
      node.createPublisher<FileChunkReply>(auv::bench::pongTopic(options), profileOf(options));
  bool stopped = false;
  uint64_t echoed = 0;
  auto sub = node.createSubscription<FileChunkReply>(
      auv::bench::pingTopic(options), profileOf(options), [&](const FileChunkReply& ping) {
        if (ping.header().sequence_number() == kStopSequence) {
          stopped = true;
          return;
        }
        pub->publish(ping);
        ++echoed;
      });
  executor.spinUntil([&stopped] { return stopped; }, seconds(options.timeout_s));
  auto fields = auv::bench::commonFields(kTool, options.vendor, options);
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
  session.report(auv::bench::commonFields(kTool, options.vendor, options));
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
  ai::Executor executor;
  executor.add(node);
  auv::bench::ThroughputSink sink(options);
  auto sub = node.createSubscription<FileChunkReply>(
      auv::bench::dataTopic(options), profileOf(options), [&sink](const FileChunkReply& m) {
        sink.onSample(m.header().sequence_number(), m.data().size());
      });
  const int64_t start = nowNs();
  while (!sink.finished(start)) executor.spinOnce(std::chrono::milliseconds(100));
  sink.report(auv::bench::commonFields(kTool, options.vendor, options));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  BenchOptions options;
  try {
    options = auv::bench::parseOptions(argc, argv, "auv_dds_bench", true, false);
  } catch (const std::invalid_argument& e) {
    std::cerr << e.what() << "\n" << auv::bench::usage("auv_dds_bench", true, false);
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
