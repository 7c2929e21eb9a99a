// The Cyclone DDS source of the graph inspector: reads Cyclone's built-in topics
// DCPSParticipant, DCPSPublication and DCPSSubscription, which list local and remote
// participants and endpoints of every vendor on the wire, with topic, type and QoS.
#include "auv/interfaces/graph.h"

#include <cstring>
#include <map>
#include <mutex>
#include <stdexcept>

#include <dds/dds.h>

#include "../cyclonedds/cyclone_config.h"

namespace auv::interfaces {

// ---------------------------------------------------------------------------------------
// Cyclone DDS source.
// ---------------------------------------------------------------------------------------

namespace detail {
namespace {

void check(dds_return_t rc, const std::string& what) {
  if (rc < 0)
    throw std::runtime_error("GraphInspector (cyclonedds): " + what + ": " + dds_strretcode(rc));
}

Guid toGuid(const dds_guid_t& g) {
  Guid guid;
  std::memcpy(guid.data(), g.v, 16);
  return guid;
}

// Seconds as QosProfile counts them: infinite -> 0.
double toSeconds(dds_duration_t d) {
  return d == DDS_INFINITY ? 0.0 : static_cast<double>(d) / 1e9;
}

// What a Cyclone endpoint QoS announces, as a QosProfile. Cyclone fills absent policies with
// the DDS defaults for the endpoint kind before handing the sample out.
QosProfile toProfile(const dds_qos_t* q, bool is_writer) {
  QosProfile p;
  p.name.clear();
  dds_reliability_kind_t reliability;
  dds_duration_t blocking;
  p.reliability = is_writer ? Reliability::RELIABLE : Reliability::BEST_EFFORT;
  if (dds_qget_reliability(q, &reliability, &blocking)) {
    p.reliability =
        reliability == DDS_RELIABILITY_RELIABLE ? Reliability::RELIABLE : Reliability::BEST_EFFORT;
    p.max_blocking_time_s = toSeconds(blocking);
  }
  dds_durability_kind_t durability;
  p.durability = Durability::VOLATILE;
  if (dds_qget_durability(q, &durability))
    p.durability =
        durability == DDS_DURABILITY_VOLATILE ? Durability::VOLATILE : Durability::TRANSIENT_LOCAL;
  dds_history_kind_t history;
  int32_t depth;
  p.history = History::KEEP_LAST;
  p.depth = 1;
  if (dds_qget_history(q, &history, &depth)) {
    p.history = history == DDS_HISTORY_KEEP_ALL ? History::KEEP_ALL : History::KEEP_LAST;
    p.depth = depth;
  }
  dds_duration_t deadline;
  p.deadline_s = dds_qget_deadline(q, &deadline) ? toSeconds(deadline) : 0.0;
  dds_liveliness_kind_t liveliness;
  dds_duration_t lease;
  p.liveliness = Liveliness::AUTOMATIC;
  p.liveliness_lease_s = 0.0;
  if (dds_qget_liveliness(q, &liveliness, &lease)) {
    p.liveliness = liveliness == DDS_LIVELINESS_AUTOMATIC ? Liveliness::AUTOMATIC
                                                          : Liveliness::MANUAL_BY_TOPIC;
    p.liveliness_lease_s = toSeconds(lease);
  }
  int32_t max_samples, max_instances, max_per_instance;
  if (dds_qget_resource_limits(q, &max_samples, &max_instances, &max_per_instance)) {
    p.max_samples = max_samples;
    p.max_instances = max_instances;
    p.max_samples_per_instance = max_per_instance;
  }
  return p;
}

// Reads the three built-in topics of the participant's domain. Each data_available event
// and each poll() takes everything pending: a valid alive sample is an appearance or QoS
// change, a not-alive instance state (disposed or no writers) a departure.
class CycloneGraphSource : public GraphSource {
 public:
  CycloneGraphSource(int domain_id, GraphSink& sink) : sink_(sink) {
    ensureCycloneDomain(domain_id);
    dds_qos_t* q = dds_create_qos();
    const std::string user_data =
        participantUserData(Vendor::CYCLONEDDS, GraphInspector::kParticipantName);
    dds_qset_userdata(q, user_data.data(), user_data.size());
    dds_qset_entity_name(q, GraphInspector::kParticipantName);
    participant_ = dds_create_participant(static_cast<dds_domainid_t>(domain_id), q, nullptr);
    dds_delete_qos(q);
    check(participant_, "create participant on domain " + std::to_string(domain_id));
    dds_guid_t g;
    const dds_return_t guid_rc = dds_get_guid(participant_, &g);
    if (guid_rc < 0) dds_delete(participant_);
    check(guid_rc, "get participant guid");
    guid_ = toGuid(g);
    // Readers first, listener after: a callback never sees a half-built source.
    const dds_entity_t topics[3] = {DDS_BUILTIN_TOPIC_DCPSPARTICIPANT,
                                    DDS_BUILTIN_TOPIC_DCPSPUBLICATION,
                                    DDS_BUILTIN_TOPIC_DCPSSUBSCRIPTION};
    dds_listener_t* listener = dds_create_listener(this);
    dds_lset_data_available(listener, &CycloneGraphSource::onDataAvailable);
    dds_return_t rc = 0;
    for (int i = 0; i < 3 && rc >= 0; ++i)
      rc = readers_[i] = dds_create_reader(participant_, topics[i], nullptr, nullptr);
    for (int i = 0; i < 3 && rc >= 0; ++i) rc = dds_set_listener(readers_[i], listener);
    dds_delete_listener(listener);
    if (rc < 0) {
      dds_delete(participant_);
      check(rc, "create built-in topic readers");
    }
    poll();  // the state present at creation
  }

  // Deleting the participant deletes the readers and waits for running listeners.
  ~CycloneGraphSource() override { dds_delete(participant_); }

  Guid guid() const override { return guid_; }

  void poll() override {
    std::lock_guard<std::mutex> lock(mutex_);
    drain(0);
    drain(1);
    drain(2);
  }

 private:
  static void onDataAvailable(dds_entity_t, void* arg) {
    static_cast<CycloneGraphSource*>(arg)->poll();
  }

  // Takes everything pending on readers_[index] (0 participants, 1 writers, 2 readers).
  void drain(int index) {
    const dds_entity_t reader = readers_[index];
    constexpr int kBatch = 64;
    for (;;) {
      void* samples[kBatch] = {nullptr};  // nullptr: Cyclone loans the buffers
      dds_sample_info_t infos[kBatch];
      const dds_return_t n = dds_take(reader, samples, infos, kBatch, kBatch);
      if (n <= 0) return;
      for (int i = 0; i < n; ++i) handle(index, samples[i], infos[i]);
      dds_return_loan(reader, samples, n);
      if (n < kBatch) return;
    }
  }

  void handle(int index, const void* sample, const dds_sample_info_t& info) {
    auto& guids = guids_[index];
    if (info.instance_state != DDS_IST_ALIVE) {
      // A disposed/unregistered instance: its key is the instance handle we recorded.
      auto it = guids.find(info.instance_handle);
      if (it == guids.end()) return;
      if (index == 0) {
        sink_.participantGone(it->second);
      } else {
        sink_.endpointGone(it->second);
      }
      guids.erase(it);
      return;
    }
    if (!info.valid_data) return;
    if (index == 0) {
      const auto* p = static_cast<const dds_builtintopic_participant_t*>(sample);
      std::string user_data, name;
      void* value = nullptr;
      size_t size = 0;
      if (dds_qget_userdata(p->qos, &value, &size) && value != nullptr)
        user_data.assign(static_cast<const char*>(value), size);
      dds_free(value);
      char* entity_name = nullptr;
      if (dds_qget_entity_name(p->qos, &entity_name) && entity_name != nullptr) name = entity_name;
      dds_free(entity_name);
      const Guid guid = toGuid(p->key);
      guids[info.instance_handle] = guid;
      sink_.participantSeen(makeParticipantInfo(guid, user_data, name));
    } else {
      const auto* e = static_cast<const dds_builtintopic_endpoint_t*>(sample);
      EndpointInfo out;
      out.is_writer = index == 1;
      out.topic = "/" + std::string(e->topic_name != nullptr ? e->topic_name : "");
      out.type = e->type_name != nullptr ? e->type_name : "";
      out.guid = toGuid(e->key);
      out.participant = toGuid(e->participant_key);
      out.qos = toProfile(e->qos, out.is_writer);
      // Cyclone (any version) announces history/resource limits; others do not, and
      // Cyclone then reports the defaults (keep_last 1, unlimited).
      out.history_known = vendorNameFromGuid(out.participant) == "cyclonedds";
      guids[info.instance_handle] = out.guid;
      sink_.endpointSeen(out);
    }
  }

  GraphSink& sink_;
  dds_entity_t participant_ = 0;
  dds_entity_t readers_[3] = {0, 0, 0};
  Guid guid_{};
  std::mutex mutex_;                                // serialises drains
  std::map<dds_instance_handle_t, Guid> guids_[3];  // instance -> key, per reader
};

}  // namespace

std::unique_ptr<GraphSource> createCycloneGraphSource(int domain_id, GraphSink& sink) {
  return std::make_unique<CycloneGraphSource>(domain_id, sink);
}

}  // namespace detail
}  // namespace auv::interfaces
