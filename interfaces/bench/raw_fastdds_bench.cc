// raw_fastdds_bench: the Fast DDS anchor. Same roles, topics, message type
// (auv::msg::FileChunkReply through its fastddsgen PubSubType), QoS and transport as
// auv_dds_bench on Fast DDS, written directly against the Fast DDS 2.9 DCPS API, so the
// difference between the two is the cost of our layer. Settings mirrored from
// src/fastdds/fastdds_backend.cc: one UDPv4 transport whitelisted to 127.0.0.1 with 4 MiB
// socket buffers and the builtin transports off, data sharing off, PREALLOCATED_WITH_REALLOC
// history memory, unlimited resource limits, max_blocking_time 0.1 s, synchronous publish mode (the
// default), type information and type object not sent.
//
// --dispatch listener (default): take and answer inside on_data_available, the fastest a
//   Fast DDS application can react (like ddsperf's default for Cyclone).
// --dispatch thread: the listener only wakes the main thread, which takes and answers, the
//   structure of our layer (listener -> Waker -> executor thread).

#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <iostream>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

#include "auv/msg/recorder.h"
#include "auv/msg/recorderPubSubTypes.h"
#include "bench_common.h"

namespace {

namespace dds = eprosima::fastdds::dds;
using auv::bench::BenchOptions;
using auv::bench::Dispatch;
using auv::bench::kStopSequence;
using auv::bench::nowNs;
using auv::msg::FileChunkReply;
using eprosima::fastrtps::types::ReturnCode_t;

constexpr const char* kTool = "raw_fastdds";
constexpr auto kPollPeriod = std::chrono::milliseconds(20);

void check(bool ok, const std::string& what) {
  if (!ok) throw std::runtime_error("raw_fastdds_bench: " + what + " failed");
}

// The endpoint QoS our layer derives from the `command` / `sensor_data` profiles.
template <class EndpointQos>
void applyProfile(const BenchOptions& options, EndpointQos& q) {
  const bool reliable = options.qos == "command";
  q.reliability().kind =
      reliable ? dds::RELIABLE_RELIABILITY_QOS : dds::BEST_EFFORT_RELIABILITY_QOS;
  q.reliability().max_blocking_time = eprosima::fastrtps::Duration_t(0.1);
  q.durability().kind = dds::VOLATILE_DURABILITY_QOS;
  q.history().kind = dds::KEEP_LAST_HISTORY_QOS;
  q.history().depth = reliable ? 10 : 5;
  q.resource_limits().max_samples = 0;  // unlimited in Fast DDS 2.9
  q.resource_limits().max_instances = 0;
  q.resource_limits().max_samples_per_instance = 0;
  q.endpoint().history_memory_policy =
      eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
  q.data_sharing().off();
}

class Listener : public dds::DataReaderListener {
 public:
  explicit Listener(std::function<void()> on_data) : on_data_(std::move(on_data)) {}
  void on_data_available(dds::DataReader*) override { on_data_(); }

 private:
  std::function<void()> on_data_;
};

// One participant with one publisher and one subscriber, as our layer creates per node.
class RawParticipant {
 public:
  explicit RawParticipant(const BenchOptions& options) : options_(options) {
    dds::DomainParticipantQos qos;
    auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
    udp->interfaceWhiteList.emplace_back("127.0.0.1");
    udp->receiveBufferSize = 4 * 1024 * 1024;  // as our layer
    udp->sendBufferSize = 4 * 1024 * 1024;
    qos.transport().user_transports.push_back(udp);
    qos.transport().use_builtin_transports = false;
    qos.name("raw_fastdds_bench");
    participant_ =
        dds::DomainParticipantFactory::get_instance()->create_participant(options.domain, qos);
    check(participant_ != nullptr,
          "create participant on domain " + std::to_string(options.domain));
    dds::TypeSupport type(new auv::msg::FileChunkReplyPubSubType());
    type->auto_fill_type_information(false);  // as our layer (Cyclone rejects it)
    type->auto_fill_type_object(false);
    check(participant_->register_type(type) == ReturnCode_t::RETCODE_OK, "register type");
    type_name_ = type.get_type_name();
    publisher_ = participant_->create_publisher(dds::PUBLISHER_QOS_DEFAULT);
    subscriber_ = participant_->create_subscriber(dds::SUBSCRIBER_QOS_DEFAULT);
    check(publisher_ != nullptr && subscriber_ != nullptr, "create publisher/subscriber");
  }
  ~RawParticipant() {
    participant_->delete_contained_entities();
    dds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
  }
  RawParticipant(const RawParticipant&) = delete;
  RawParticipant& operator=(const RawParticipant&) = delete;

  dds::DataWriter* createWriter(const std::string& topic) {
    dds::DataWriterQos qos = publisher_->get_default_datawriter_qos();
    applyProfile(options_, qos);
    dds::DataWriter* writer = publisher_->create_datawriter(createTopic(topic), qos);
    check(writer != nullptr, "create writer on " + topic);
    return writer;
  }

  dds::DataReader* createReader(const std::string& topic, Listener* listener) {
    dds::DataReaderQos qos = subscriber_->get_default_datareader_qos();
    applyProfile(options_, qos);
    dds::DataReader* reader = subscriber_->create_datareader(createTopic(topic), qos, listener,
                                                             dds::StatusMask::data_available());
    check(reader != nullptr, "create reader on " + topic);
    return reader;
  }
  dds::Subscriber* subscriber() { return subscriber_; }

 private:
  dds::Topic* createTopic(const std::string& name) {
    dds::Topic* topic = participant_->create_topic(name, type_name_, dds::TOPIC_QOS_DEFAULT);
    check(topic != nullptr, "create topic " + name);
    return topic;
  }

  BenchOptions options_;
  dds::DomainParticipant* participant_ = nullptr;
  dds::Publisher* publisher_ = nullptr;
  dds::Subscriber* subscriber_ = nullptr;
  std::string type_name_;
};

int matchedReaders(dds::DataWriter* writer) {
  dds::PublicationMatchedStatus status;
  writer->get_publication_matched_status(status);
  return status.current_count;
}

int matchedWriters(dds::DataReader* reader) {
  dds::SubscriptionMatchedStatus status;
  reader->get_subscription_matched_status(status);
  return status.current_count;
}

bool waitFor(const std::function<bool()>& done, double timeout_s) {
  const int64_t deadline = nowNs() + static_cast<int64_t>(timeout_s * 1e9);
  while (!done()) {
    if (nowNs() > deadline) return false;
    std::this_thread::sleep_for(kPollPeriod);
  }
  return true;
}

FileChunkReply makeMessage(uint32_t size) {
  FileChunkReply message;
  message.data().resize(size);
  for (uint32_t i = 0; i < size; ++i) message.data()[i] = static_cast<uint8_t>(i * 131u + 7u);
  return message;
}

std::vector<std::pair<std::string, std::string>> fieldsOf(const BenchOptions& options) {
  auto fields = auv::bench::commonFields(kTool, "fastdds", options);
  fields.emplace_back("dispatch", auv::bench::toString(options.dispatch));
  return fields;
}

int reportNoMatch(const BenchOptions& options) {
  auto fields = fieldsOf(options);
  fields.emplace_back("status", "no_match");
  auv::bench::printResult(fields);
  std::cerr << "raw_fastdds_bench: no match on domain " << options.domain << "\n";
  return 1;
}

// Reception shared by all roles: in listener mode `handle` runs in the Fast DDS thread, in
// thread mode the listener only flags and the main thread calls drain().
class Receiver {
 public:
  Receiver(const BenchOptions& options, std::function<void(const FileChunkReply&)> handle)
      : options_(options), handle_(std::move(handle)), listener_([this] { onData(); }) {}
  /// Deletes the reader first: no listener call may outlive this object.
  ~Receiver() {
    if (reader_ == nullptr) return;
    reader_->set_listener(nullptr);
    subscriber_->delete_datareader(reader_);
  }
  Receiver(const Receiver&) = delete;
  Receiver& operator=(const Receiver&) = delete;
  void attach(dds::Subscriber* subscriber, dds::DataReader* reader) {
    std::lock_guard<std::mutex> lock(mutex_);
    subscriber_ = subscriber;
    reader_ = reader;
  }
  Listener* listener() { return &listener_; }
  std::mutex& mutex() { return mutex_; }
  /// Waits (lock held) up to `timeout` for data (thread mode) and drains it.
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
  /// Takes every available sample into the reused sample and handles it: in the listener
  /// under our mutex (listener mode), or on the main thread without it (thread mode).
  void drain() {
    if (reader_ == nullptr) return;
    dds::SampleInfo info;
    while (reader_->take_next_sample(&sample_, &info) == ReturnCode_t::RETCODE_OK) {
      if (info.valid_data) handle_(sample_);
    }
  }

 private:
  // Listener mode wakes nobody: the main thread only polls for the end of the run, so the
  // anchor pays no wake-up per sample (as ddsperf).
  void onData() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (options_.dispatch == Dispatch::THREAD) {
      pending_ = true;
      cv_.notify_one();
    } else {
      drain();
    }
  }

  BenchOptions options_;
  std::function<void(const FileChunkReply&)> handle_;
  Listener listener_;
  std::mutex mutex_;
  std::condition_variable cv_;
  bool pending_ = false;
  dds::Subscriber* subscriber_ = nullptr;
  dds::DataReader* reader_ = nullptr;
  FileChunkReply sample_;  // reused: deserialization keeps the payload buffer's capacity
};

int runPing(RawParticipant& participant, const BenchOptions& options) {
  auv::bench::PingSession session(options);
  FileChunkReply ping = makeMessage(options.size);
  dds::DataWriter* writer = participant.createWriter(auv::bench::pingTopic(options));
  auto send = [&] {
    ping.header().sequence_number(session.startPing());
    ping.offset(static_cast<uint64_t>(nowNs()));
    writer->write(&ping);
  };
  Receiver receiver(options, [&](const FileChunkReply& pong) {
    if (session.onPong(pong.header().sequence_number(), pong.data().size()) &&
        options.dispatch == Dispatch::LISTENER && !session.finished())
      send();  // next ping straight from the listener
  });
  dds::DataReader* reader =
      participant.createReader(auv::bench::pongTopic(options), receiver.listener());
  receiver.attach(participant.subscriber(), reader);
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
  FileChunkReply stop;
  stop.header().sequence_number(kStopSequence);
  for (int i = 0; i < 3; ++i) {
    writer->write(&stop);
    std::this_thread::sleep_for(kPollPeriod);
  }
  std::lock_guard<std::mutex> lock(receiver.mutex());
  session.report(fieldsOf(options));
  return 0;
}

int runPong(RawParticipant& participant, const BenchOptions& options) {
  dds::DataWriter* writer = participant.createWriter(auv::bench::pongTopic(options));
  bool stopped = false;
  uint64_t echoed = 0;
  Receiver receiver(options, [&](const FileChunkReply& ping) {
    if (ping.header().sequence_number() == kStopSequence) {
      stopped = true;
      return;
    }
    writer->write(const_cast<FileChunkReply*>(&ping));
    ++echoed;
  });
  receiver.attach(participant.subscriber(),
                  participant.createReader(auv::bench::pingTopic(options), receiver.listener()));
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
  dds::DataWriter* writer = participant.createWriter(auv::bench::dataTopic(options));
  if (!waitFor([&] { return matchedReaders(writer) > 0; }, options.timeout_s))
    return reportNoMatch(options);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // let the reader match us too

  auv::bench::PublishSession session(options);
  FileChunkReply message = makeMessage(options.size);
  session.start();
  while (session.running()) {
    message.header().sequence_number(session.nextSequence());
    message.offset(static_cast<uint64_t>(nowNs()));
    if (!writer->write(&message)) session.onWriteFailed();
  }
  session.report(fieldsOf(options));
  FileChunkReply stop;
  stop.header().sequence_number(kStopSequence);
  for (int i = 0; i < 3; ++i) {
    writer->write(&stop);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  return 0;
}

int runSub(RawParticipant& participant, const BenchOptions& options) {
  auv::bench::ThroughputSink sink(options);
  Receiver receiver(options, [&sink](const FileChunkReply& m) {
    sink.onSample(m.header().sequence_number(), m.data().size());
  });
  receiver.attach(participant.subscriber(),
                  participant.createReader(auv::bench::dataTopic(options), receiver.listener()));
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
    options = auv::bench::parseOptions(argc, argv, "raw_fastdds_bench", auv::bench::Program::RAW);
  } catch (const std::invalid_argument& e) {
    std::cerr << e.what() << "\n"
              << auv::bench::usage("raw_fastdds_bench", auv::bench::Program::RAW);
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
    std::cerr << "raw_fastdds_bench: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
