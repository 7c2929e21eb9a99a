// Fast DDS backend: the DDS-DCPS C++ API with the fastddsgen TopicDataTypes.
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

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <map>
#include <mutex>
#include <optional>
#include <stdexcept>

#include "auv/interfaces/backend.h"
#include "fastdds_config.h"
#include "fastdds_raw_type.h"
#include "serialized_sample.h"

namespace auv::interfaces::detail {
namespace {

namespace dds = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;

void check(bool ok, const std::string& what) {
  if (!ok) throw std::runtime_error("fastdds: " + what + " failed");
}

constexpr uint32_t kSocketBufferBytes = 4 * 1024 * 1024;  // loopback transport, see below
constexpr double kNackSuppressionS = 1e-3;                // reliable writers, see createWriter

eprosima::fastrtps::Duration_t toDuration(double seconds) {
  if (seconds <= 0) return eprosima::fastrtps::c_TimeInfinite;
  return eprosima::fastrtps::Duration_t(seconds);
}

// The parts of the profile common to readers and writers.
template <class EndpointQos>
void applyCommon(const QosProfile& p, EndpointQos& q) {
  q.reliability().kind = p.reliability == Reliability::RELIABLE ? dds::RELIABLE_RELIABILITY_QOS
                                                                : dds::BEST_EFFORT_RELIABILITY_QOS;
  q.reliability().max_blocking_time = toDuration(p.max_blocking_time_s);
  q.durability().kind = p.durability == Durability::TRANSIENT_LOCAL
                            ? dds::TRANSIENT_LOCAL_DURABILITY_QOS
                            : dds::VOLATILE_DURABILITY_QOS;
  q.history().kind =
      p.history == History::KEEP_LAST ? dds::KEEP_LAST_HISTORY_QOS : dds::KEEP_ALL_HISTORY_QOS;
  q.history().depth = p.depth;
  q.deadline().period = toDuration(p.deadline_s);
  q.liveliness().kind = p.liveliness == Liveliness::AUTOMATIC ? dds::AUTOMATIC_LIVELINESS_QOS
                                                              : dds::MANUAL_BY_TOPIC_LIVELINESS_QOS;
  q.liveliness().lease_duration = toDuration(p.liveliness_lease_s);
  if (p.liveliness_lease_s > 0)  // Fast DDS requires announcement period < lease duration
    q.liveliness().announcement_period = toDuration(p.liveliness_lease_s * 0.5);
  // Fast DDS defaults (10 instances, 5000 samples) would silently cap keyed topics. In
  // Fast DDS 2.9 "unlimited" is 0 here: LENGTH_UNLIMITED (-1) makes keyed writes fail.
  q.resource_limits().max_samples = p.max_samples > 0 ? p.max_samples : 0;
  q.resource_limits().max_instances = p.max_instances > 0 ? p.max_instances : 0;
  q.resource_limits().max_samples_per_instance =
      p.max_samples_per_instance > 0 ? p.max_samples_per_instance : 0;
  // Messages have unbounded sequences: payloads are sized per sample.
  q.endpoint().history_memory_policy =
      eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
  q.data_sharing().off();
}

std::string returnCodeName(const ReturnCode_t& rc) {
  switch (rc()) {
    case ReturnCode_t::RETCODE_TIMEOUT:
      return "timeout (history full of samples a reader has not acknowledged)";
    case ReturnCode_t::RETCODE_OUT_OF_RESOURCES:
      return "out of resources";
    case ReturnCode_t::RETCODE_NOT_ENABLED:
      return "writer not enabled";
    case ReturnCode_t::RETCODE_BAD_PARAMETER:
      return "bad parameter";
    default:
      return "return code " + std::to_string(rc());
  }
}

Guid toGuid(const eprosima::fastrtps::rtps::GUID_t& g) {
  Guid guid;
  std::memcpy(guid.data(), g.guidPrefix.value, 12);
  std::memcpy(guid.data() + 12, g.entityId.value, 4);
  return guid;
}

// The participant with its one publisher and subscriber. Shared by the participant and every
// reader/writer, so a reader or writer that outlives its Node still deletes itself safely.
struct DomainEntities {
  dds::DomainParticipant* participant = nullptr;
  dds::Publisher* publisher = nullptr;
  dds::Subscriber* subscriber = nullptr;
  ~DomainEntities() {
    if (participant == nullptr) return;
    participant->delete_contained_entities();
    dds::DomainParticipantFactory::get_instance()->delete_participant(participant);
  }
};

class FastddsWriter : public DataWriter {
 public:
  FastddsWriter(std::shared_ptr<DomainEntities> domain, dds::DataWriter* writer,
                double max_blocking_time_s)
      : domain_(std::move(domain)),
        writer_(writer),
        max_blocking_(max_blocking_time_s > 0
                          ? std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                std::chrono::duration<double>(max_blocking_time_s))
                          : std::chrono::hours(24 * 365)) {}  // 0: infinite (toDuration)
  ~FastddsWriter() override { domain_->publisher->delete_datawriter(writer_); }
  void write(const void* sample) override {
    // A reliable keep-all writer whose history is full waits for acknowledgements, but Fast
    // DDS 2.9 returns TIMEOUT as soon as the acknowledgement that frees room arrives (once per
    // history's worth of samples, docs/performance.md), long before max_blocking_time: write
    // again until max_blocking_time has really passed, as the QoS promises.
    const auto deadline = std::chrono::steady_clock::now() + max_blocking_;
    for (;;) {
      const ReturnCode_t rc = writer_->write(const_cast<void*>(sample),
                                             eprosima::fastrtps::rtps::c_InstanceHandle_Unknown);
      if (rc == ReturnCode_t::RETCODE_OK) return;
      if (rc != ReturnCode_t::RETCODE_TIMEOUT || std::chrono::steady_clock::now() >= deadline) {
        throw std::runtime_error("fastdds: write on '" + writer_->get_topic()->get_name() +
                                 "' failed: " + returnCodeName(rc));
      }
    }
  }
  int matchedReaders() const override {
    dds::PublicationMatchedStatus status;
    return writer_->get_publication_matched_status(status) == ReturnCode_t::RETCODE_OK
               ? status.current_count
               : 0;
  }
  bool waitForAcknowledgments(double timeout_s) override {
    return writer_->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(timeout_s)) ==
           ReturnCode_t::RETCODE_OK;
  }
  Guid guid() const override { return toGuid(writer_->guid()); }

 private:
  std::shared_ptr<DomainEntities> domain_;
  dds::DataWriter* writer_;
  std::chrono::steady_clock::duration max_blocking_;
};

int64_t toNanoseconds(const eprosima::fastrtps::rtps::Time_t& t) {
  return static_cast<int64_t>(t.seconds()) * 1000000000LL + t.nanosec();
}

SampleInfo toSampleInfo(const dds::SampleInfo& si) {
  SampleInfo info;
  info.source_timestamp_ns = toNanoseconds(si.source_timestamp);
  std::memcpy(info.publication.data(), si.publication_handle.value, 16);
  info.reception_timestamp_ns = toNanoseconds(si.reception_timestamp);
  info.sequence_number = si.sample_identity.sequence_number().to64long();
  if (info.sequence_number <= 0) info.sequence_number = -1;  // SequenceNumber_t::unknown()
  return info;
}

/// The samples a batch take deserializes into: of the reader's type, made by its TopicDataType
/// and reused from take to take (they keep their buffers, as the single-sample path does).
/// Owned, not loaned: Fast DDS 2.9's loaning take segfaults on 4 MiB samples from a Cyclone
/// writer (auv_dds_bench, command profile).
class SampleBuffers : public dds::LoanableCollection {
 public:
  SampleBuffers(dds::TypeSupport type, size_type count) : type_(std::move(type)) { resize(count); }
  ~SampleBuffers() {
    for (size_type i = 0; i < maximum_; ++i) type_.delete_data(elements_[i]);
    delete[] elements_;
  }
  SampleBuffers(const SampleBuffers&) = delete;
  SampleBuffers& operator=(const SampleBuffers&) = delete;

 protected:
  void resize(size_type count) override {  // grows only; a take never asks beyond maximum()
    if (count <= maximum_) return;
    auto* grown = new element_type[count];
    std::copy(elements_, elements_ + maximum_, grown);
    for (size_type i = maximum_; i < count; ++i) grown[i] = type_.create_data();
    delete[] elements_;
    elements_ = grown;
    maximum_ = count;
  }

 private:
  dds::TypeSupport type_;
};

class FastddsReader : public DataReader, public dds::DataReaderListener {
 public:
  explicit FastddsReader(DataCallback on_data) : on_data_(std::move(on_data)) {}
  ~FastddsReader() override {
    {
      // Fast DDS 2.9 may still be inside on_data_available after set_listener(nullptr):
      // wait for a running callback and keep new ones out before the reader goes.
      std::lock_guard<std::mutex> lock(callback_mutex_);
      closed_ = true;
    }
    if (reader_ != nullptr) {
      reader_->set_listener(nullptr);
      domain_->subscriber->delete_datareader(reader_);
    }
  }
  void attach(std::shared_ptr<DomainEntities> domain, dds::DataReader* reader) {
    std::lock_guard<std::mutex> lock(callback_mutex_);
    domain_ = std::move(domain);
    reader_ = reader;
  }
  bool take(void* sample, SampleInfo* info) override {
    dds::SampleInfo si;
    while (reader_->take_next_sample(sample, &si) == ReturnCode_t::RETCODE_OK) {
      if (!si.valid_data) continue;
      if (info != nullptr) *info = toSampleInfo(si);
      return true;
    }
    return false;
  }
  /// The whole batch under one hold of the reader's mutex instead of one per sample. Per
  /// sample, the mutex was contended by the thread delivering the next sample (in process the
  /// publisher's own) and most samples cost both threads a futex sleep and wake-up.
  int takeBatch(void* scratch, int max, const SampleVisitor& visit) override {
    if (!samples_) {
      samples_ = std::make_unique<SampleBuffers>(reader_->type(), kMaxBatch);
      infos_ = std::make_unique<dds::SampleInfoSeq>(kMaxBatch);
    }
    // A take appends after a collection's length: empty both first.
    samples_->length(0);
    infos_->length(0);
    const ReturnCode_t rc = reader_->take(*samples_, *infos_, std::min(max, kMaxBatch));
    if (rc == ReturnCode_t::RETCODE_NO_DATA) return 0;
    // Refused (e.g. a precondition of this Fast DDS): one at a time, never a stalled reader.
    if (rc != ReturnCode_t::RETCODE_OK) return DataReader::takeBatch(scratch, max, visit);
    std::exception_ptr first_error;
    const dds::SampleInfoSeq& infos = *infos_;
    for (dds::LoanableCollection::size_type i = 0; i < infos.length(); ++i) {
      if (!infos[i].valid_data) continue;
      try {
        visit(samples_->buffer()[i], toSampleInfo(infos[i]));
      } catch (...) {  // the rest of the batch is taken already: visit it, then rethrow
        if (!first_error) first_error = std::current_exception();
      }
    }
    if (first_error) std::rethrow_exception(first_error);
    return infos.length();
  }
  int matchedWriters() const override {
    dds::SubscriptionMatchedStatus status;
    return reader_->get_subscription_matched_status(status) == ReturnCode_t::RETCODE_OK
               ? status.current_count
               : 0;
  }
  Guid guid() const override { return toGuid(reader_->guid()); }
  void on_data_available(dds::DataReader* reader) override {
    std::lock_guard<std::mutex> lock(callback_mutex_);
    if (closed_ || !on_data_) return;
    // Fast DDS may call this before create_datareader returns (history of a writer in the
    // same participant): take() then needs the reader already. attach() stores the same.
    if (reader_ == nullptr) reader_ = reader;
    on_data_(*this);
  }

 private:
  DataCallback on_data_;
  std::mutex callback_mutex_;
  bool closed_ = false;
  std::shared_ptr<DomainEntities> domain_;
  dds::DataReader* reader_ = nullptr;
  std::unique_ptr<SampleBuffers> samples_;  // takeBatch's, made on its first call
  std::unique_ptr<dds::SampleInfoSeq> infos_;
};

// The builtin DDS Security plugins of Fast DDS (PKI-DH, Access-Permissions, AES-GCM-GMAC)
// configured by participant properties; docs/security.md.
void addSecurityProperties(const SecurityFiles& files, dds::DomainParticipantQos& qos) {
  auto& properties = qos.properties().properties();
  // Fast DDS 2.9 accepts only "file://" + absolute path ("file:" alone is "unsupported").
  const std::string file = "file://";
  const auto add = [&properties](const std::string& name, const std::string& value) {
    properties.emplace_back(name, value);
  };
  add("dds.sec.auth.plugin", "builtin.PKI-DH");
  add("dds.sec.auth.builtin.PKI-DH.identity_ca", file + files.identity_ca);
  add("dds.sec.auth.builtin.PKI-DH.identity_certificate", file + files.certificate);
  add("dds.sec.auth.builtin.PKI-DH.private_key", file + files.private_key);
  add("dds.sec.access.plugin", "builtin.Access-Permissions");
  add("dds.sec.access.builtin.Access-Permissions.permissions_ca", file + files.permissions_ca);
  add("dds.sec.access.builtin.Access-Permissions.governance", file + files.governance);
  add("dds.sec.access.builtin.Access-Permissions.permissions", file + files.permissions);
  add("dds.sec.crypto.plugin", "builtin.AES-GCM-GMAC");
}

}  // namespace

dds::DomainParticipantQos fastddsParticipantQos(const ParticipantOptions& options) {
  auto* factory = dds::DomainParticipantFactory::get_instance();
  dds::DomainParticipantQos qos;
  const char* profiles = std::getenv("FASTRTPS_DEFAULT_PROFILES_FILE");
  if (profiles != nullptr && *profiles != '\0') {
    // XML profiles only apply through load_profiles + the factory default (docs/library-notes.md).
    static std::once_flag loaded;
    std::call_once(loaded, [factory] { factory->load_profiles(); });
    qos = factory->get_default_participant_qos();
  } else {
    // Loopback only: one UDPv4 transport on 127.0.0.1, no shared memory, no other interface.
    auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
    udp->interfaceWhiteList.emplace_back("127.0.0.1");
    // 4 MiB socket buffers instead of the system default (~208 KiB): a large sample's 64 KB
    // datagrams then fit without drops and repair rounds. The kernel silently caps them at
    // net.core.rmem_max / wmem_max. Measured in docs/performance.md.
    udp->receiveBufferSize = kSocketBufferBytes;
    udp->sendBufferSize = kSocketBufferBytes;
    qos.transport().user_transports.push_back(udp);
    qos.transport().use_builtin_transports = false;
  }
  if (const std::optional<SecurityFiles> security = participantSecurity(options))
    addSecurityProperties(*security, qos);
  qos.name(options.node_name);
  const std::string user_data = participantUserData(Vendor::FASTDDS, options.node_name);
  qos.user_data().setValue(
      std::vector<eprosima::fastrtps::rtps::octet>(user_data.begin(), user_data.end()));
  return qos;
}

namespace {

class FastddsParticipant : public Participant {
 public:
  explicit FastddsParticipant(const ParticipantOptions& options)
      : domain_(std::make_shared<DomainEntities>()) {
    auto* factory = dds::DomainParticipantFactory::get_instance();
    domain_->participant =
        factory->create_participant(options.domain_id, fastddsParticipantQos(options));
    participant_ = domain_->participant;
    check(participant_ != nullptr,
          "create participant on domain " + std::to_string(options.domain_id) +
              (participantSecurity(options) ? " with DDS Security (certificate, key, governance "
                                              "or permissions rejected: see the log above)"
                                            : ""));
    publisher_ = domain_->publisher = participant_->create_publisher(dds::PUBLISHER_QOS_DEFAULT);
    subscriber_ = domain_->subscriber =
        participant_->create_subscriber(dds::SUBSCRIBER_QOS_DEFAULT);
    check(publisher_ != nullptr && subscriber_ != nullptr, "create publisher/subscriber");
  }

  Vendor vendor() const override { return Vendor::FASTDDS; }
  Guid guid() const override { return toGuid(participant_->guid()); }

  std::unique_ptr<DataWriter> createWriter(const std::string& topic, const msg::TypeSupport& type,
                                           const QosProfile& qos) override {
    return makeWriter(topic, type, qos, false);
  }

  std::unique_ptr<DataReader> createReader(const std::string& topic, const msg::TypeSupport& type,
                                           const QosProfile& qos, DataCallback on_data) override {
    return makeReader(topic, type, qos, std::move(on_data), false);
  }

  std::unique_ptr<SerializedWriter> createSerializedWriter(const std::string& topic,
                                                           const msg::TypeSupport& type,
                                                           const QosProfile& qos) override {
    return makeSerializedWriter(makeWriter(topic, type, qos, true), type);
  }

  std::unique_ptr<SerializedReader> createSerializedReader(
      const std::string& topic, const msg::TypeSupport& type, const QosProfile& qos,
      SerializedDataCallback on_data) override {
    auto adapter = std::make_unique<SerializedReaderAdapter>(std::move(on_data));
    adapter->attach(makeReader(topic, type, qos, adapter->dataCallback(), true));
    return adapter;
  }

 private:
  // `serialized`: over RawPubSubType, moving RawSamples (serialized_sample.h).
  std::unique_ptr<DataWriter> makeWriter(const std::string& topic, const msg::TypeSupport& type,
                                         const QosProfile& qos, bool serialized) {
    dds::Topic* t = createTopic(topic, type, serialized);
    dds::DataWriterQos wqos = publisher_->get_default_datawriter_qos();
    applyCommon(qos, wqos);
    // Fast DDS heartbeats every 3 s by default, so a late joiner (transient local) or a
    // lost fragment waited up to 3 s; 0.25 s keeps repair prompt at little cost.
    wqos.reliable_writer_qos().times.heartbeatPeriod = eprosima::fastrtps::Duration_t(0.25);
    // With the default nack suppression of 0, every sample sent to a remote reader wakes the
    // event thread, which then takes the writer's mutex against the next write: a futex
    // sleep and wake-up per sample. 1 ms lets one event cover all the samples sent meanwhile;
    // it only delays the repair of a sample NACKed within 1 ms of sending it.
    wqos.reliable_writer_qos().times.nackSupressionDuration =
        eprosima::fastrtps::Duration_t(kNackSuppressionS);
    dds::DataWriter* w = publisher_->create_datawriter(t, wqos);
    check(w != nullptr, "create writer on '" + topic + "'");
    return std::make_unique<FastddsWriter>(domain_, w, qos.max_blocking_time_s);
  }

  std::unique_ptr<DataReader> makeReader(const std::string& topic, const msg::TypeSupport& type,
                                         const QosProfile& qos, DataCallback on_data,
                                         bool serialized) {
    dds::Topic* t = createTopic(topic, type, serialized);
    dds::DataReaderQos rqos = subscriber_->get_default_datareader_qos();
    applyCommon(qos, rqos);
    // Keep-all readers acknowledge a heartbeat at once (Fast DDS waits 5 ms by default): a
    // keep-all writer frees its history only on acknowledgements, and a Fast DDS writer asks
    // for them only when its history is full, so every history's worth of samples stalled the
    // writer for the delay (docs/performance.md, "Keep-all streams"). Not keep-last readers:
    // a keep-last writer's history is always full, so it asks with every sample, and answering
    // each at once halved Fast DDS's reliable keep-last throughput; the delay batches those.
    if (qos.history == History::KEEP_ALL) {
      rqos.reliable_reader_qos().times.heartbeatResponseDelay =
          eprosima::fastrtps::Duration_t(0, 0);
    }
    auto reader = std::make_unique<FastddsReader>(std::move(on_data));
    dds::DataReader* r =
        subscriber_->create_datareader(t, rqos, reader.get(), dds::StatusMask::data_available());
    check(r != nullptr, "create reader on '" + topic + "'");
    reader->attach(domain_, r);
    return reader;
  }

  dds::Topic* createTopic(const std::string& topic, const msg::TypeSupport& type, bool serialized) {
    const std::string name = toDdsTopicName(topic);
    std::lock_guard<std::mutex> lock(mutex_);
    // One TopicDataType per type name and participant: typed or raw, never both.
    const auto kind = serialized_types_.emplace(type.name, serialized).first;
    if (kind->second != serialized)
      throw std::runtime_error(
          "fastdds: type " + type.name + " is used by " + (kind->second ? "serialized" : "typed") +
          " endpoints of this participant; " + (serialized ? "serialized" : "typed") +
          " endpoints of it need a participant of their own");
    if (participant_->find_type(type.name).empty()) {
      dds::TypeSupport support(serialized ? new RawPubSubType(type) : type.make_topic_data_type());
      // Type information would make Cyclone reject our discovery data (docs/library-notes.md).
      support->auto_fill_type_information(false);
      support->auto_fill_type_object(false);
      check(participant_->register_type(support) == ReturnCode_t::RETCODE_OK,
            "register type " + type.name);
    }
    auto it = topics_.find(name);
    if (it != topics_.end()) {
      if (it->second->get_type_name() != type.name)
        throw std::runtime_error("topic '" + topic + "' already has type " +
                                 it->second->get_type_name() + ", not " + type.name);
      return it->second;
    }
    dds::Topic* t = participant_->create_topic(name, type.name, dds::TOPIC_QOS_DEFAULT);
    check(t != nullptr, "create topic '" + topic + "' of type " + type.name);
    topics_[name] = t;
    return t;
  }

  std::shared_ptr<DomainEntities> domain_;
  dds::DomainParticipant* participant_ = nullptr;  // shortcuts into domain_
  dds::Publisher* publisher_ = nullptr;
  dds::Subscriber* subscriber_ = nullptr;
  std::mutex mutex_;
  std::map<std::string, dds::Topic*> topics_;
  std::map<std::string, bool> serialized_types_;  // type name -> registered as raw
};

}  // namespace

std::unique_ptr<Participant> createFastddsParticipant(const ParticipantOptions& options) {
  return std::make_unique<FastddsParticipant>(options);
}

}  // namespace auv::interfaces::detail
