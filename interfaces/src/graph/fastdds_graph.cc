// GraphInspector's Fast DDS source: a participant without endpoints whose
// DomainParticipantListener receives every remote participant, writer and reader found by
// the simple discovery protocols (SPDP/SEDP), of any vendor, and their removal.
#include "auv/interfaces/graph.h"

#include "../fastdds/fastdds_config.h"

#include <cstring>
#include <stdexcept>

#include <fastdds/rtps/builtin/data/ParticipantProxyData.h>
#include <fastdds/rtps/builtin/data/ReaderProxyData.h>
#include <fastdds/rtps/builtin/data/WriterProxyData.h>
#include <fastdds/rtps/participant/ParticipantDiscoveryInfo.h>
#include <fastdds/rtps/reader/ReaderDiscoveryInfo.h>
#include <fastdds/rtps/writer/WriterDiscoveryInfo.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>

namespace auv::interfaces::detail {
namespace {

namespace dds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastrtps::rtps;

Guid toGuid(const rtps::GUID_t& g) {
  Guid guid;
  std::memcpy(guid.data(), g.guidPrefix.value, 12);
  std::memcpy(guid.data() + 12, g.entityId.value, 4);
  return guid;
}

// The owning participant's GUID: same prefix, entity id 0x000001c1.
Guid participantGuid(const rtps::GUID_t& endpoint) {
  return toGuid(rtps::GUID_t(endpoint.guidPrefix, rtps::c_EntityId_RTPSParticipant));
}

// Seconds as QosProfile counts them: infinite -> 0.
double toSeconds(const eprosima::fastrtps::Duration_t& d) {
  return d == eprosima::fastrtps::c_TimeInfinite ? 0.0 : d.to_ns() / 1e9;
}

// What an endpoint announced. ReaderQos and WriterQos (the discovery-data QoS, not the
// DDS entity QoS) have the same member names. They carry no history and no resource limits:
// those are not in the standard SEDP data and Fast DDS 2.9 ignores Cyclone's extra PIDs.
template <class DiscoveredQos>
QosProfile toProfile(const DiscoveredQos& q) {
  QosProfile p;
  p.name.clear();
  p.reliability = q.m_reliability.kind == dds::RELIABLE_RELIABILITY_QOS ? Reliability::RELIABLE
                                                                        : Reliability::BEST_EFFORT;
  p.max_blocking_time_s = toSeconds(q.m_reliability.max_blocking_time);
  p.durability = q.m_durability.kind == dds::VOLATILE_DURABILITY_QOS ? Durability::VOLATILE
                                                                     : Durability::TRANSIENT_LOCAL;
  p.history = History::KEEP_LAST;  // the DDS default, shown as unknown (history_known)
  p.depth = 1;
  p.deadline_s = toSeconds(q.m_deadline.period);
  p.liveliness = q.m_liveliness.kind == dds::AUTOMATIC_LIVELINESS_QOS ? Liveliness::AUTOMATIC
                                                                      : Liveliness::MANUAL_BY_TOPIC;
  p.liveliness_lease_s = toSeconds(q.m_liveliness.lease_duration);
  p.max_samples = -1;
  p.max_instances = -1;
  p.max_samples_per_instance = -1;
  return p;
}

template <class ProxyData>
EndpointInfo toEndpoint(const ProxyData& data, bool is_writer) {
  EndpointInfo out;
  out.is_writer = is_writer;
  out.topic = "/" + data.topicName().to_string();
  out.type = data.typeName().to_string();
  out.guid = toGuid(data.guid());
  out.participant = participantGuid(data.guid());
  out.qos = toProfile(data.m_qos);
  out.history_known = false;
  return out;
}

// Fast DDS calls the listener from its discovery threads, once per change; the sink keeps
// the state. The participant's own entities are not reported by Fast DDS.
class FastddsGraphSource : public GraphSource, public dds::DomainParticipantListener {
 public:
  FastddsGraphSource(int domain_id, GraphSink& sink) : sink_(sink) {
    ParticipantOptions options;
    options.domain_id = domain_id;
    options.node_name = GraphInspector::kParticipantName;
    // The listener may be called before create_participant returns: sink_ is ready.
    participant_ = dds::DomainParticipantFactory::get_instance()->create_participant(
        domain_id, fastddsParticipantQos(options), this, dds::StatusMask::none());
    if (participant_ == nullptr)
      throw std::runtime_error("GraphInspector (fastdds): create participant on domain " +
                               std::to_string(domain_id) + " failed");
    guid_ = toGuid(participant_->guid());
  }

  // Deleting the participant stops its threads: no callback runs afterwards.
  ~FastddsGraphSource() override {
    dds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
  }

  Guid guid() const override { return guid_; }

  void on_participant_discovery(dds::DomainParticipant*,
                                rtps::ParticipantDiscoveryInfo&& info) override {
    const Guid guid = toGuid(info.info.m_guid);
    switch (info.status) {
      case rtps::ParticipantDiscoveryInfo::DISCOVERED_PARTICIPANT:
      case rtps::ParticipantDiscoveryInfo::CHANGED_QOS_PARTICIPANT: {
        const auto& bytes = info.info.m_userData.getValue();
        sink_.participantSeen(makeParticipantInfo(guid, std::string(bytes.begin(), bytes.end()),
                                                  info.info.m_participantName.to_string()));
        break;
      }
      case rtps::ParticipantDiscoveryInfo::REMOVED_PARTICIPANT:  // announced its departure
      case rtps::ParticipantDiscoveryInfo::DROPPED_PARTICIPANT:  // lease expired
        sink_.participantGone(guid);
        break;
    }
  }

  void on_subscriber_discovery(dds::DomainParticipant*, rtps::ReaderDiscoveryInfo&& info) override {
    if (info.status == rtps::ReaderDiscoveryInfo::REMOVED_READER) {
      sink_.endpointGone(toGuid(info.info.guid()));
    } else {
      sink_.endpointSeen(toEndpoint(info.info, false));
    }
  }

  void on_publisher_discovery(dds::DomainParticipant*, rtps::WriterDiscoveryInfo&& info) override {
    if (info.status == rtps::WriterDiscoveryInfo::REMOVED_WRITER) {
      sink_.endpointGone(toGuid(info.info.guid()));
    } else {
      sink_.endpointSeen(toEndpoint(info.info, true));
    }
  }

 private:
  GraphSink& sink_;
  dds::DomainParticipant* participant_ = nullptr;
  Guid guid_{};
};

}  // namespace

std::unique_ptr<GraphSource> createFastddsGraphSource(int domain_id, GraphSink& sink) {
  return std::make_unique<FastddsGraphSource>(domain_id, sink);
}

}  // namespace auv::interfaces::detail
