#pragma once
// Named QoS profiles. A topic's profile is declared once, next to its use, and can be
// overridden from parameters/launch files by name. Each profile is a complete set so both
// vendors are configured identically (what does not match, does not communicate).

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace auv::interfaces {

enum class Reliability { BEST_EFFORT, RELIABLE };
enum class Durability { VOLATILE, TRANSIENT_LOCAL };
enum class History { KEEP_LAST, KEEP_ALL };
enum class Liveliness { AUTOMATIC, MANUAL_BY_TOPIC };

/// A complete QoS profile. Durations in seconds; 0 means infinite where noted.
struct QosProfile {
  std::string name;  ///< Profile name, e.g. "sensor_data".
  Reliability reliability = Reliability::RELIABLE;
  Durability durability = Durability::VOLATILE;
  History history = History::KEEP_LAST;
  int32_t depth = 10;       ///< History depth for KEEP_LAST (samples).
  double deadline_s = 0.0;  ///< Max period between samples; 0 = none.
  Liveliness liveliness = Liveliness::AUTOMATIC;
  double liveliness_lease_s = 0.0;        ///< Liveliness lease duration; 0 = infinite.
  int32_t max_samples = -1;               ///< Resource limit; -1 = unlimited.
  int32_t max_instances = -1;             ///< Resource limit; -1 = unlimited.
  int32_t max_samples_per_instance = -1;  ///< Resource limit; -1 = unlimited.
  double max_blocking_time_s = 0.1;       ///< How long a reliable write may block.

  /// Throws std::invalid_argument naming the field when the profile is inconsistent
  /// (e.g. best effort + transient local, which delivers nothing historical across vendors).
  void check() const;
  /// One-line human-readable summary ("reliable, transient_local, keep_last(1), ...").
  std::string summary() const;
};

/// Streams from sensors: best effort, volatile, keep last 5; losing a sample beats lagging.
QosProfile sensorDataQos();
/// Vehicle state (odometry, status): reliable, volatile, keep last 1, 0.5 s deadline.
QosProfile stateQos();
/// Map updates: reliable, transient local, keep last 2 per instance (late joiners get the map;
/// a FULL map and the increment of the same version both reach a reader).
QosProfile mapQos();
/// Commands and queries: reliable, volatile, keep last 10, never dropped silently.
QosProfile commandQos();
/// Bulk data (file chunks, catalogues): reliable, volatile, keep all, bounded resources.
QosProfile bulkTransferQos();
/// Viewing-only topics (trees, paths): best effort, keep last 1.
QosProfile viewingQos();
/// Latched state (mission status): reliable, transient local, keep last 1.
QosProfile latchedStateQos();
/// The simulation `clock`: best effort, keep last 1 (only the newest time matters).
QosProfile clockQos();

/// The profile called `name` (sensor_data, state, map, command, bulk_transfer, viewing,
/// latched_state); throws std::invalid_argument listing the known names otherwise.
QosProfile qosProfileByName(const std::string& name);
/// Names accepted by qosProfileByName.
std::vector<std::string> qosProfileNames();

}  // namespace auv::interfaces
