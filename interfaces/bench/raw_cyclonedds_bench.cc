// raw_cyclonedds_bench: a second Cyclone DDS anchor beside ddsperf. Same roles, topics and
// QoS as auv_dds_bench, same message type on the wire (auv::msg::FileChunkReply, here as the
// idlc-generated C type with Cyclone's own serializer), written against the plain Cyclone C
// API. ddsperf measures Cyclone with its own keyed type; this program measures it with our
// type, so `ours / raw_cyclonedds` isolates the cost of our layer (custom sertype over the
// fastddsgen code, executor hand-off), and raw_cyclonedds <-> raw_fastdds pairs give the
// vendor-only figure for the cross-vendor rows.
//
// Settings mirrored from src/cyclonedds/cyclone_backend.cc: the same loopback domain
// configuration (unless CYCLONEDDS_URI is set), reliability with max_blocking_time 0.1 s,
// volatile, keep-last depth, unlimited resource limits, XCDR1 data representation.

#include <dds/dds.h>

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <iostream>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "bench_common.h"
#include "recorder.h"  // idlc output for auv_msgs' recorder.idl

namespace {

using auv::bench::BenchOptions;
using auv::bench::Dispatch;
using auv::bench::kStopSequence;
using auv::bench::nowNs;
using Sample = auv_msg_FileChunkReply;

constexpr const char* kTool = "raw_cyclonedds";
constexpr auto kPollPeriod = std::chrono::milliseconds(20);

// Identical to kLoopbackConfig in src/cyclonedds/cyclone_backend.cc.
constexpr const char* kLoopbackConfig =
    "<CycloneDDS><Domain Id=\"any\"><General><Interfaces>"
    "<NetworkInterface name=\"lo\" multicast=\"true\"/>"
    "</Interfaces><AllowMulticast>true</AllowMulticast></General>"
    "<Internal><SocketReceiveBufferSize min=\"default\" max=\"4MB\"/></Internal>"
    "</Domain></CycloneDDS>";

char kEmpty[] = "";

dds_entity_t check(dds_entity_t rc, const std::string& what) {
  if (rc < 0) throw std::runtime_error("raw_cyclonedds_bench: " + what + ": " + dds_strretcode(rc));
  return rc;
}

// The QoS our layer derives from the `command` / `sensor_data` profiles.
dds_qos_t* makeQos(const BenchOptions& options) {
  const bool reliable = options.qos == "command";
  dds_qos_t* q = dds_create_qos();
  dds_qset_reliability(q, reliable ? DDS_RELIABILITY_RELIABLE : DDS_RELIABILITY_BEST_EFFORT,
                       DDS_MSECS(100));
  dds_qset_durability(q, DDS_DURABILITY_VOLATILE);
  dds_qset_history(q, DDS_HISTORY_KEEP_LAST, reliable ? 10 : 5);
  dds_qset_deadline(q, DDS_INFINITY);
  dds_qset_liveliness(q, DDS_LIVELINESS_AUTOMATIC, DDS_INFINITY);
  dds_qset_resource_limits(q, -1, -1, -1);
  const dds_data_representation_id_t xcdr1 = DDS_DATA_REPRESENTATION_XCDR1;
  dds_qset_data_representation(q, 1, &xcdr1);
  return q;
}

// A sample whose payload points at `payload` (not owned: _release false).
Sample borrowedSample(std::vector<uint8_t>& payload) {
  Sample s{};
  s.file_path = kEmpty;
  s.status.error_text = kEmpty;
  s.data._buffer = payload.data();
  s.data._length = static_cast<uint32_t>(payload.size());
  s.data._maximum = static_cast<uint32_t>(payload.size());
  s.data._release = false;
  return s;
}

std::vector<uint8_t> makePayload(uint32_t size) {
  std::vector<uint8_t> payload(size);
  for (uint32_t i = 0; i < size; ++i) payload[i] = static_cast<uint8_t>(i * 131u + 7u);
  return payload;
}

class RawParticipant {
 public:
  explicit RawParticipant(const BenchOptions& options) : options_(options) {
    const char* uri = std::getenv("CYCLONEDDS_URI");
    if (uri == nullptr || *uri == '\0')
      domain_ =
          check(dds_create_domain(static_cast<dds_domainid_t>(options.domain), kLoopbackConfig),
                "create domain " + std::to_string(options.domain));
    participant_ =
        check(dds_create_participant(static_cast<dds_domainid_t>(options.domain), nullptr, nullptr),
              "create participant");
  }
  ~RawParticipant() {
    dds_delete(participant_);
    if (domain_ > 0) dds_delete(domain_);
  }
  RawParticipant(const RawParticipant&) = delete;
  RawParticipant& operator=(const RawParticipant&) = delete;

  dds_entity_t createWriter(const std::string& topic) {
    dds_qos_t* q = makeQos(options_);
    const dds_entity_t w = dds_create_writer(participant_, createTopic(topic), q, nullptr);
    dds_delete_qos(q);
    return check(w, "create writer on " + topic);
  }
  dds_entity_t createReader(const std::string& topic, dds_listener_t* listener) {
    dds_qos_t* q = makeQos(options_);
    const dds_entity_t r = dds_create_reader(participant_, createTopic(topic), q, listener);
    dds_delete_qos(q);
    return check(r, "create reader on " + topic);
  }

 private:
  dds_entity_t createTopic(const std::string& name) {
    return check(dds_create_topic(participant_, &auv_msg_FileChunkReply_desc, name.c_str(), nullptr,
                                  nullptr),
                 "create topic " + name);
  }

  BenchOptions options_;
  dds_entity_t domain_ = 0;
  dds_entity_t participant_ = 0;
};

int matchedReaders(dds_entity_t writer) {
  dds_publication_matched_status_t s;
  return dds_get_publication_matched_status(writer, &s) == 0 ? static_cast<int>(s.current_count)
                                                             : 0;
}

int matchedWriters(dds_entity_t reader) {
  dds_subscription_matched_status_t s;
  return dds_get_subscription_matched_status(reader, &s) == 0 ? static_cast<int>(s.current_count)
                                                              : 0;
}

bool waitFor(const std::function<bool()>& done, double timeout_s) {
  const int64_t deadline = nowNs() + static_cast<int64_t>(timeout_s * 1e9);
  while (!done()) {
    if (nowNs() > deadline) return false;
    std::this_thread::sleep_for(kPollPeriod);
  }
  return true;
}

std::vector<std::pair<std::string, std::string>> fieldsOf(const BenchOptions& options) {
  auto fields = auv::bench::commonFields(kTool, "cyclonedds", options);
  fields.emplace_back("dispatch", auv::bench::toString(options.dispatch));
  return fields;
}

int reportNoMatch(const BenchOptions& options) {
  auto fields = fieldsOf(options);
  fields.emplace_back("status", "no_match");
  auv::bench::printResult(fields);
  std::cerr << "raw_cyclonedds_bench: no match on domain " << options.domain << "\n";
  return 1;
}

// Reception shared by all roles; see raw_fastdds_bench.cc. Takes into one reused sample
// (Cyclone reallocates its payload buffer only when a larger one arrives).
class Receiver {
 public:
  Receiver(const BenchOptions& options, std::function<void(const Sample&)> handle)
      : options_(options), handle_(std::move(handle)), listener_(dds_create_listener(this)) {
    dds_lset_data_available(listener_, &Receiver::onDataAvailable);
  }
  ~Receiver() {
    if (reader_ > 0) dds_delete(reader_);  // waits for a running listener call
    dds_delete_listener(listener_);
    dds_sample_free(&sample_, &auv_msg_FileChunkReply_desc, DDS_FREE_CONTENTS);
  }
  Receiver(const Receiver&) = delete;
  Receiver& operator=(const Receiver&) = delete;
  dds_listener_t* listener() { return listener_; }
  void attach(dds_entity_t reader) {
    std::lock_guard<std::mutex> lock(mutex_);
    reader_ = reader;
  }
  std::mutex& mutex() { return mutex_; }
  void waitAndDrain(std::unique_lock<std::mutex>& lock, std::chrono::nanoseconds timeout) {
    if (options_.dispatch == Dispatch::THREAD) {
      cv_.wait_for(lock, timeout, [this] { return pending_; });
      pending_ = false;
      // Take without our mutex: the vendor calls the listener holding its reader lock, and
      // the listener takes our mutex (lock order reader -> ours; never the reverse).
      lock.unlock();
      drain();
      lock.lock();
    } else {
      cv_.wait_for(lock, timeout);  // listener mode: a poll period (the listener does the work)
    }
  }
  void drain() {
    if (reader_ <= 0) return;
    for (;;) {
      void* buffers[1] = {&sample_};
      dds_sample_info_t info;
      if (dds_take(reader_, buffers, &info, 1, 1) <= 0) return;
      if (info.valid_data) handle_(sample_);
    }
  }

 private:
  static void onDataAvailable(dds_entity_t, void* arg) {
    auto* self = static_cast<Receiver*>(arg);
    std::lock_guard<std::mutex> lock(self->mutex_);
    // Listener mode wakes nobody: the main thread only polls for the end of the run.
    if (self->options_.dispatch == Dispatch::THREAD) {
      self->pending_ = true;
      self->cv_.notify_one();
    } else {
      self->drain();
    }
  }

  BenchOptions options_;
  std::function<void(const Sample&)> handle_;
  dds_listener_t* listener_;
  std::mutex mutex_;
  std::condition_variable cv_;
  bool pending_ = false;
  dds_entity_t reader_ = 0;
  Sample sample_{};
};

int runPing(RawParticipant& participant, const BenchOptions& options) {
  auv::bench::PingSession session(options);
  std::vector<uint8_t> payload = makePayload(options.size);
  Sample ping = borrowedSample(payload);
  const dds_entity_t writer = participant.createWriter(auv::bench::pingTopic(options));
  auto send = [&] {
    ping.header.sequence_number = session.startPing();
    ping.offset = static_cast<uint64_t>(nowNs());
    dds_write(writer, &ping);
  };
  Receiver receiver(options, [&](const Sample& pong) {
    if (session.onPong(pong.header.sequence_number, pong.data._length) &&
        options.dispatch == Dispatch::LISTENER && !session.finished())
      send();
  });
  const dds_entity_t reader =
      participant.createReader(auv::bench::pongTopic(options), receiver.listener());
  receiver.attach(reader);
  if (!waitFor([&] { return matchedReaders(writer) > 0 && matchedWriters(reader) > 0; },
               options.timeout_s))
    return reportNoMatch(options);

  const int64_t deadline = nowNs() + static_cast<int64_t>(options.timeout_s * 1e9);
  {
    std::unique_lock<std::mutex> lock(receiver.mutex());
    send();
    while (!session.finished() && nowNs() < deadline) {
      receiver.waitAndDrain(lock, std::chrono::milliseconds(50));
      if (session.finished()) break;
      if (session.awaiting() && session.outstandingNs() > options.ping_timeout_s * 1e9)
        session.abandonPing();
      if (!session.awaiting()) send();
    }
  }
  std::vector<uint8_t> empty;
  Sample stop = borrowedSample(empty);
  stop.header.sequence_number = kStopSequence;
  for (int i = 0; i < 3; ++i) {
    dds_write(writer, &stop);
    std::this_thread::sleep_for(kPollPeriod);
  }
  std::lock_guard<std::mutex> lock(receiver.mutex());
  session.report(fieldsOf(options));
  return 0;
}

int runPong(RawParticipant& participant, const BenchOptions& options) {
  const dds_entity_t writer = participant.createWriter(auv::bench::pongTopic(options));
  bool stopped = false;
  uint64_t echoed = 0;
  Receiver receiver(options, [&](const Sample& ping) {
    if (ping.header.sequence_number == kStopSequence) {
      stopped = true;
      return;
    }
    dds_write(writer, &ping);
    ++echoed;
  });
  receiver.attach(participant.createReader(auv::bench::pingTopic(options), receiver.listener()));
  const int64_t deadline = nowNs() + static_cast<int64_t>(options.timeout_s * 1e9);
  {
    std::unique_lock<std::mutex> lock(receiver.mutex());
    while (!stopped && nowNs() < deadline)
      receiver.waitAndDrain(lock, std::chrono::milliseconds(50));
  }
  auto fields = fieldsOf(options);
  fields.insert(fields.end(),
                {{"status", stopped ? "ok" : "timeout"}, {"echoed", std::to_string(echoed)}});
  auv::bench::printResult(fields);
  return stopped ? 0 : 1;
}

int runPub(RawParticipant& participant, const BenchOptions& options) {
  const dds_entity_t writer = participant.createWriter(auv::bench::dataTopic(options));
  if (!waitFor([&] { return matchedReaders(writer) > 0; }, options.timeout_s))
    return reportNoMatch(options);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // let the reader match us too

  auv::bench::PublishSession session(options);
  std::vector<uint8_t> payload = makePayload(options.size);
  Sample message = borrowedSample(payload);
  session.start();
  while (session.running()) {
    message.header.sequence_number = session.nextSequence();
    message.offset = static_cast<uint64_t>(nowNs());
    if (dds_write(writer, &message) < 0) session.onWriteFailed();
  }
  session.report(fieldsOf(options));
  std::vector<uint8_t> empty;
  Sample stop = borrowedSample(empty);
  stop.header.sequence_number = kStopSequence;
  for (int i = 0; i < 3; ++i) {
    dds_write(writer, &stop);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  return 0;
}

int runSub(RawParticipant& participant, const BenchOptions& options) {
  auv::bench::ThroughputSink sink(options);
  Receiver receiver(options, [&sink](const Sample& m) {
    sink.onSample(m.header.sequence_number, m.data._length);
  });
  receiver.attach(participant.createReader(auv::bench::dataTopic(options), receiver.listener()));
  const int64_t start = nowNs();
  {
    std::unique_lock<std::mutex> lock(receiver.mutex());
    while (!sink.finished(start)) receiver.waitAndDrain(lock, std::chrono::milliseconds(100));
  }
  std::lock_guard<std::mutex> lock(receiver.mutex());
  sink.report(fieldsOf(options));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  BenchOptions options;
  try {
    options =
        auv::bench::parseOptions(argc, argv, "raw_cyclonedds_bench", auv::bench::Program::RAW);
  } catch (const std::invalid_argument& e) {
    std::cerr << e.what() << "\n"
              << auv::bench::usage("raw_cyclonedds_bench", auv::bench::Program::RAW);
    return 2;
  }
  try {
    RawParticipant participant(options);
    switch (options.role) {
      case auv::bench::Role::PING:
        return runPing(participant, options);
      case auv::bench::Role::PONG:
        return runPong(participant, options);
      case auv::bench::Role::PUB:
        return runPub(participant, options);
      case auv::bench::Role::SUB:
        return runSub(participant, options);
    }
  } catch (const std::exception& e) {
    std::cerr << "raw_cyclonedds_bench: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
