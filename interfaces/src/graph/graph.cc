// GraphInspector: the vendor-neutral front end (snapshot, waitFor, USER_DATA parsing). The
// vendor sources (cyclone_graph.cc, fastdds_graph.cc) feed it discovery events.
#include "auv/interfaces/graph.h"

#include <algorithm>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <map>
#include <mutex>
#include <stdexcept>
#include <tuple>

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

QosProfile compatibleReaderQos(const std::vector<EndpointInfo>& writers, int32_t depth) {
  QosProfile qos;
  qos.name = "compatible";
  qos.reliability = writers.empty() ? Reliability::BEST_EFFORT : Reliability::RELIABLE;
  qos.durability = writers.empty() ? Durability::VOLATILE : Durability::TRANSIENT_LOCAL;
  qos.history = History::KEEP_LAST;
  qos.depth = std::max<int32_t>(depth, 1);
  for (const EndpointInfo& w : writers) {
    if (w.qos.reliability != Reliability::RELIABLE) qos.reliability = Reliability::BEST_EFFORT;
    if (w.qos.durability != Durability::TRANSIENT_LOCAL) qos.durability = Durability::VOLATILE;
    if (w.history_known && w.qos.history == History::KEEP_LAST)
      qos.depth = std::max(qos.depth, w.qos.depth);
  }
  // A best-effort transient-local reader delivers nothing historical across vendors
  // (QosProfile::check): such writers are read as volatile.
  if (qos.reliability == Reliability::BEST_EFFORT) qos.durability = Durability::VOLATILE;
  qos.deadline_s = 0;
  qos.liveliness = Liveliness::AUTOMATIC;
  qos.liveliness_lease_s = 0;
  return qos;
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

}  // namespace auv::interfaces
