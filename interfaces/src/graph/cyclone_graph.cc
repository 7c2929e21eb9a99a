// GraphInspector: the vendor-neutral front end (snapshot, waitFor, USER_DATA parsing) and the
// Cyclone DDS source, which reads Cyclone's built-in topics DCPSParticipant,
// DCPSPublication and DCPSSubscription. Those list local and remote participants and
// endpoints of every vendor on the wire, with topic, type and QoS.
//
// The front end lives here because this folder's file list is fixed to one source per
// vendor; it has no Cyclone dependency and can move to a graph.cc of its own.
#include "auv/interfaces/graph.h"

#include "../cyclonedds/cyclone_config.h"

#include <algorithm>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <map>
#include <mutex>
#include <stdexcept>
#include <tuple>

#include <dds/dds.h>

namespace auv::interfaces {

// ---------------------------------------------------------------------------------------
// Vendor-neutral part.
// ---------------------------------------------------------------------------------------

namespace {

// "/a/b" for "a/b" or "/a/b"; how snapshots name topics.
std::string graphTopicName(const std::string& topic) {
  return !topic.empty() && topic.front() == '/' ? topic : "/" + topic;
}

}  // namespace

std::string vendorNameFromGuid(const Guid& guid) {
  const unsigned id = (static_cast<unsigned>(guid[0]) << 8) | guid[1];
  switch (id) {
    case 0x010f:
      return "fastdds";
    case 0x0110:
      return "cyclonedds";
    case 0x0101:
      return "connext";
    case 0x0103:
      return "opendds";
    default:
      break;
  }
  char hex[32];
  std::snprintf(hex, sizeof(hex), "vendor 0x%04x", id);
  return hex;
}

namespace detail {

ParticipantInfo makeParticipantInfo(const Guid& guid, const std::string& user_data,
                                    const std::string& dds_name) {
  ParticipantInfo info;
  info.guid = guid;
  info.node_name = dds_name;
  info.vendor = vendorNameFromGuid(guid);
  // participantUserData(): "auv:node=<name>;host=<hostname>;pid=<pid>;vendor=<vendor>".
  // Some stacks pad USER_DATA; cut at the first NUL.
  const std::string text = user_data.substr(0, user_data.find('\0'));
  static const std::string kPrefix = "auv:";
  if (text.compare(0, kPrefix.size(), kPrefix) != 0) return info;
  std::map<std::string, std::string> fields;
  size_t begin = kPrefix.size();
  while (begin <= text.size()) {
    size_t end = text.find(';', begin);
    if (end == std::string::npos) end = text.size();
    const std::string item = text.substr(begin, end - begin);
    const size_t eq = item.find('=');
    if (eq != std::string::npos) fields[item.substr(0, eq)] = item.substr(eq + 1);
    begin = end + 1;
  }
  if (!fields.count("node")) return info;  // not ours after all
  info.is_auv = true;
  info.node_name = fields["node"];
  info.host = fields["host"];
  try {
    info.pid = std::stoi(fields["pid"]);
  } catch (const std::exception&) {
    info.pid = 0;
  }
  if (!fields["vendor"].empty()) info.vendor = fields["vendor"];
  return info;
}

}  // namespace detail

std::map<std::string, std::set<std::string>> GraphSnapshot::topicTypes() const {
  std::map<std::string, std::set<std::string>> result;
  for (const EndpointInfo& e : endpoints) result[e.topic].insert(e.type);
  return result;
}

const ParticipantInfo* GraphSnapshot::participant(const Guid& guid) const {
  for (const ParticipantInfo& p : participants)
    if (p.guid == guid) return &p;
  return nullptr;
}

std::vector<EndpointInfo> GraphSnapshot::endpointsOn(const std::string& topic, bool writers) const {
  const std::string name = graphTopicName(topic);
  std::vector<EndpointInfo> result;
  for (const EndpointInfo& e : endpoints)
    if (e.topic == name && e.is_writer == writers) result.push_back(e);
  return result;
}

bool GraphSnapshot::hasTopic(const std::string& topic) const {
  const std::string name = graphTopicName(topic);
  return std::any_of(endpoints.begin(), endpoints.end(),
                     [&](const EndpointInfo& e) { return e.topic == name; });
}

// The discovery cache both vendor sources feed.
class GraphInspector::Impl : public detail::GraphSink {
 public:
  Impl(Vendor vendor, int domain_id) : vendor_(vendor), domain_id_(domain_id) {
    if (domain_id < 0 || domain_id > 232)
      throw std::invalid_argument("GraphInspector: domain id " + std::to_string(domain_id) +
                                  " outside [0, 232]");
    source_ = vendor == Vendor::CYCLONEDDS ? detail::createCycloneGraphSource(domain_id, *this)
                                           : detail::createFastddsGraphSource(domain_id, *this);
    own_guid_ = source_->guid();
  }
  // The source goes first: after it, no middleware thread calls the sink any more.
  ~Impl() override { source_.reset(); }

  void participantSeen(const ParticipantInfo& info) override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      participants_[info.guid] = info;
      ++version_;
    }
    changed_.notify_all();
  }
  void participantGone(const Guid& guid) override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      participants_.erase(guid);
      for (auto it = endpoints_.begin(); it != endpoints_.end();)
        it = it->second.participant == guid ? endpoints_.erase(it) : std::next(it);
      ++version_;
    }
    changed_.notify_all();
  }
  void endpointSeen(const EndpointInfo& info) override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      endpoints_[info.guid] = info;
      ++version_;
    }
    changed_.notify_all();
  }
  void endpointGone(const Guid& guid) override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      endpoints_.erase(guid);
      ++version_;
    }
    changed_.notify_all();
  }

  GraphSnapshot snapshot(uint64_t* version) {
    source_->poll();
    std::lock_guard<std::mutex> lock(mutex_);
    if (version != nullptr) *version = version_;
    GraphSnapshot snap;
    std::set<Guid> hidden = {own_guid_};
    for (const auto& [guid, p] : participants_) {
      if (guid == own_guid_ || p.node_name == kParticipantName) {
        hidden.insert(guid);
        continue;
      }
      snap.participants.push_back(p);
    }
    for (const auto& [guid, e] : endpoints_)
      if (!hidden.count(e.participant)) snap.endpoints.push_back(e);
    std::sort(snap.participants.begin(), snap.participants.end(),
              [](const ParticipantInfo& a, const ParticipantInfo& b) {
                return std::tie(a.node_name, a.guid) < std::tie(b.node_name, b.guid);
              });
    std::sort(snap.endpoints.begin(), snap.endpoints.end(),
              [](const EndpointInfo& a, const EndpointInfo& b) {
                return std::make_tuple(a.topic, !a.is_writer, a.guid) <
                       std::make_tuple(b.topic, !b.is_writer, b.guid);
              });
    return snap;
  }

  GraphSnapshot waitFor(const std::function<bool(const GraphSnapshot&)>& pred,
                        std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      uint64_t seen = 0;
      GraphSnapshot snap = snapshot(&seen);
      if (pred(snap) || std::chrono::steady_clock::now() >= deadline) return snap;
      // Sleep until the cache changes; the 50 ms cap covers sources that only poll.
      std::unique_lock<std::mutex> lock(mutex_);
      const auto wake =
          std::min(deadline, std::chrono::steady_clock::now() + std::chrono::milliseconds(50));
      changed_.wait_until(lock, wake, [&] { return version_ != seen; });
    }
  }

  const Vendor vendor_;
  const int domain_id_;
  Guid own_guid_{};

 private:
  std::unique_ptr<detail::GraphSource> source_;
  std::mutex mutex_;
  std::condition_variable changed_;
  uint64_t version_ = 0;  // bumped on every change
  std::map<Guid, ParticipantInfo> participants_;
  std::map<Guid, EndpointInfo> endpoints_;
};

GraphInspector::GraphInspector(Vendor vendor, int domain_id)
    : impl_(std::make_unique<Impl>(vendor, domain_id)) {}

GraphInspector::~GraphInspector() = default;

Vendor GraphInspector::vendor() const { return impl_->vendor_; }
int GraphInspector::domainId() const { return impl_->domain_id_; }
Guid GraphInspector::guid() const { return impl_->own_guid_; }

GraphSnapshot GraphInspector::snapshot() const { return impl_->snapshot(nullptr); }

GraphSnapshot GraphInspector::waitFor(const std::function<bool(const GraphSnapshot&)>& pred,
                                      std::chrono::milliseconds timeout) const {
  return impl_->waitFor(pred, timeout);
}

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
