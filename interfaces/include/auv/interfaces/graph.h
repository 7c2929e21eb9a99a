#pragma once
// The DDS graph as discovery sees it: participants (nodes) and endpoints (publishers,
// subscriptions) of both vendors, for `auv topic list/info` and `auv node list`. A
// GraphInspector is a participant of its own, configured exactly like the nodes (loopback
// only unless the user set the vendor's configuration), that creates no endpoints and only
// listens to the built-in discovery traffic. Discovery is asynchronous: a fresh inspector
// knows nothing, so callers wait (waitFor) before reading the graph.

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "auv/interfaces/backend.h"
#include "auv/interfaces/qos.h"

namespace auv::interfaces {

/// One data writer or data reader seen through discovery (any vendor, any process).
struct EndpointInfo {
  std::string topic;       ///< ROS-style, with the leading '/': "/nav/odometry".
  std::string type;        ///< DDS type name as announced, e.g. "auv::msg::Odometry".
  bool is_writer = false;  ///< True for a publisher (data writer), false for a subscription.
  Guid guid{};             ///< The endpoint's GUID.
  Guid participant{};      ///< GUID of the owning participant (GraphSnapshot::participant).
  /// QoS as announced in discovery; `name` is empty. Kinds outside QosProfile's enums are
  /// folded into the nearest one (transient/persistent durability -> TRANSIENT_LOCAL,
  /// manual-by-participant liveliness -> MANUAL_BY_TOPIC). Infinite durations are 0.
  /// History kind/depth and resource limits are not part of the standard discovery data
  /// (DCPSPublication/DCPSSubscription): see `history_known`.
  QosProfile qos;
  /// True when qos.history/depth/max_samples* were really announced. When false they hold
  /// the DDS defaults (keep_last(1), unlimited) and the CLI must show them as unknown.
  /// Cyclone 0.10 endpoints announce them and a Cyclone inspector reads them; Fast DDS 2.9
  /// endpoints do not announce them, and a Fast DDS inspector drops them for every endpoint.
  bool history_known = false;
};

/// One domain participant seen through discovery: for auv processes, one node.
struct ParticipantInfo {
  Guid guid{};  ///< The participant's GUID (endpoints refer to it).
  /// From our USER_DATA ("auv:node=..."), else the DDS participant name, else "".
  std::string node_name;
  std::string host;  ///< From our USER_DATA; "" for foreign participants.
  int pid = 0;       ///< From our USER_DATA; 0 for foreign participants.
  /// From our USER_DATA ("cyclonedds"/"fastdds"), else from the GUID's vendor id (bytes
  /// 0-1, see vendorNameFromGuid).
  std::string vendor;
  bool is_auv = false;  ///< True when the participant advertises our USER_DATA.
};

/// The graph at one instant. Participants sorted by node name then GUID, endpoints by topic,
/// writers first, then GUID. The inspector itself (and every other inspector) is excluded.
struct GraphSnapshot {
  std::vector<ParticipantInfo> participants;
  std::vector<EndpointInfo> endpoints;

  /// Topic ("/name") -> the type names announced on it (more than one means a mismatch:
  /// endpoints with different type names never match).
  std::map<std::string, std::set<std::string>> topicTypes() const;
  /// The participant with `guid`, or nullptr when it is not (or no longer) known.
  const ParticipantInfo* participant(const Guid& guid) const;
  /// Writers (`writers` true) or readers on `topic` ("/a/b" or "a/b").
  std::vector<EndpointInfo> endpointsOn(const std::string& topic, bool writers) const;
  /// True when some endpoint is on `topic` ("/a/b" or "a/b").
  bool hasTopic(const std::string& topic) const;
};

/// A hidden participant that watches discovery and reports the graph of a domain.
/// Thread-safe: snapshot() and waitFor() may be called from any thread.
///
/// Both vendors see participants and endpoints of both vendors. Measured on loopback, a new
/// inspector usually knows an existing node within a few ms, but 0.7-1 s (Cyclone inspector,
/// Fast DDS endpoints) and up to 3 s (Fast DDS's announcement period) also occur, so callers
/// should wait up to ~3 s for what they expect. Departures: a Cyclone inspector sees deleted
/// endpoints and participants of either vendor go within ~0.5 s. A Fast DDS 2.9 inspector sees
/// Fast DDS departures at once but ignores Cyclone 0.10's dispose messages: a deleted Cyclone
/// endpoint stays listed until its participant goes, and a deleted Cyclone participant stays
/// until its lease expires (10 s by default). Prefer the Cyclone inspector (AUV_DDS default).
class GraphInspector {
 public:
  /// DDS participant name (and USER_DATA node name) of every inspector; participants with
  /// this node name are left out of snapshots so inspectors never list each other.
  static constexpr const char* kParticipantName = "_auv_inspector";

  /// Joins `domain_id` with a participant of `vendor` configured like the nodes' (loopback
  /// only unless CYCLONEDDS_URI / FASTRTPS_DEFAULT_PROFILES_FILE is set). Throws
  /// std::invalid_argument for a domain outside [0, 232], std::runtime_error when the
  /// participant cannot be created.
  GraphInspector(Vendor vendor, int domain_id);
  ~GraphInspector();
  GraphInspector(const GraphInspector&) = delete;
  GraphInspector& operator=(const GraphInspector&) = delete;

  Vendor vendor() const;
  int domainId() const;
  /// GUID of the inspector's own participant (never part of a snapshot).
  Guid guid() const;

  /// What has been discovered so far.
  GraphSnapshot snapshot() const;
  /// Waits until `pred(snapshot)` holds or `timeout` passes and returns the last snapshot;
  /// on timeout `pred(result)` is false, so callers tell the cases apart by re-evaluating it.
  /// Wakes on every discovery event (no polling delay beyond 50 ms).
  GraphSnapshot waitFor(const std::function<bool(const GraphSnapshot&)>& pred,
                        std::chrono::milliseconds timeout) const;

 private:
  class Impl;  // the discovery cache; defined with the front end in cyclone_graph.cc
  std::unique_ptr<Impl> impl_;
};

/// The QoS for a reader that matches every writer in `writers` (their announced QoS, e.g.
/// GraphSnapshot::endpointsOn(topic, true)): for a tool that records or relays topics it did
/// not create. Reliable only if every writer is and transient local only if every writer is
/// (a stricter reader would not match the others); no deadline and automatic liveliness with
/// an infinite lease (they accept any offer); keep last max(`depth`, each writer's announced
/// depth), so a writer's transient-local history arrives whole; unlimited resources. Without
/// writers: best effort and volatile, which matches any writer that appears later. Named
/// "compatible".
QosProfile compatibleReaderQos(const std::vector<EndpointInfo>& writers, int32_t depth = 100);

/// Vendor name from a GUID's first two bytes (the RTPS vendor id both vendors put there):
/// 0x010f "fastdds" (eProsima), 0x0110 "cyclonedds" (Eclipse), 0x0101 "connext" (RTI),
/// 0x0103 "opendds", otherwise "vendor 0x...." in hex.
std::string vendorNameFromGuid(const Guid& guid);

namespace detail {

/// Fills node_name/host/pid/vendor/is_auv of a participant from its USER_DATA (our
/// participantUserData format) and DDS participant name; `guid` is set too.
ParticipantInfo makeParticipantInfo(const Guid& guid, const std::string& user_data,
                                    const std::string& dds_name);

/// Receives discovery events from a vendor backend (called from middleware threads).
class GraphSink {
 public:
  virtual ~GraphSink() = default;
  /// A participant appeared or changed.
  virtual void participantSeen(const ParticipantInfo& info) = 0;
  /// A participant left (disposed, lease expired); its endpoints go with it.
  virtual void participantGone(const Guid& guid) = 0;
  /// An endpoint appeared or changed.
  virtual void endpointSeen(const EndpointInfo& info) = 0;
  virtual void endpointGone(const Guid& guid) = 0;
};

/// The vendor half of a GraphInspector: owns the participant, feeds the sink.
class GraphSource {
 public:
  virtual ~GraphSource() = default;
  /// GUID of the source's own participant.
  virtual Guid guid() const = 0;
  /// Delivers pending discovery events to the sink (sources that only push do nothing).
  virtual void poll() {}
};

std::unique_ptr<GraphSource> createCycloneGraphSource(int domain_id, GraphSink& sink);
std::unique_ptr<GraphSource> createFastddsGraphSource(int domain_id, GraphSink& sink);

}  // namespace detail
}  // namespace auv::interfaces
