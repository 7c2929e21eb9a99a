#include "auv/interfaces/qos.h"

#include <sstream>
#include <stdexcept>

namespace auv::interfaces {

void QosProfile::check() const {
  auto bad = [this](const std::string& field, const std::string& why) {
    throw std::invalid_argument("QoS profile '" + name + "': " + field + " " + why);
  };
  if (history == History::KEEP_LAST && depth < 1) bad("depth", "must be >= 1 for keep_last");
  if (deadline_s < 0) bad("deadline_s", "must be >= 0");
  if (liveliness_lease_s < 0) bad("liveliness_lease_s", "must be >= 0");
  if (max_blocking_time_s < 0) bad("max_blocking_time_s", "must be >= 0");
  if (reliability == Reliability::BEST_EFFORT && durability == Durability::TRANSIENT_LOCAL)
    bad("durability", "transient_local needs reliable (best effort delivers no history)");
  if (max_samples_per_instance > 0 && history == History::KEEP_LAST &&
      depth > max_samples_per_instance)
    bad("depth", "exceeds max_samples_per_instance");
}

std::string QosProfile::summary() const {
  std::ostringstream out;
  out << (reliability == Reliability::RELIABLE ? "reliable" : "best_effort") << ", "
      << (durability == Durability::TRANSIENT_LOCAL ? "transient_local" : "volatile") << ", ";
  if (history == History::KEEP_LAST)
    out << "keep_last(" << depth << ")";
  else
    out << "keep_all";
  if (deadline_s > 0) out << ", deadline " << deadline_s << " s";
  if (liveliness_lease_s > 0)
    out << ", liveliness "
        << (liveliness == Liveliness::AUTOMATIC ? "automatic" : "manual_by_topic") << " "
        << liveliness_lease_s << " s";
  return out.str();
}

QosProfile sensorDataQos() {
  QosProfile q;
  q.name = "sensor_data";
  q.reliability = Reliability::BEST_EFFORT;
  q.depth = 5;
  return q;
}

QosProfile stateQos() {
  QosProfile q;
  q.name = "state";
  q.depth = 1;
  q.deadline_s = 0.5;
  return q;
}

QosProfile mapQos() {
  QosProfile q;
  q.name = "map";
  q.durability = Durability::TRANSIENT_LOCAL;
  // 2: a FULL map goes out right behind the increment of the same version, and a reader that
  // had only the FULL left (keep last 1) would have to read and rebuild what it already holds.
  q.depth = 2;
  return q;
}

QosProfile commandQos() {
  QosProfile q;
  q.name = "command";
  q.depth = 10;
  return q;
}

QosProfile bulkTransferQos() {
  QosProfile q;
  q.name = "bulk_transfer";
  q.history = History::KEEP_ALL;
  q.max_samples = 256;  // bounds memory: a chunk is at most a few MiB
  q.max_blocking_time_s = 1.0;
  return q;
}

QosProfile viewingQos() {
  QosProfile q;
  q.name = "viewing";
  q.reliability = Reliability::BEST_EFFORT;
  q.depth = 1;
  return q;
}

QosProfile clockQos() {
  QosProfile q = viewingQos();
  q.name = "clock";
  return q;
}

QosProfile latchedStateQos() {
  QosProfile q;
  q.name = "latched_state";
  q.durability = Durability::TRANSIENT_LOCAL;
  q.depth = 1;
  return q;
}

std::vector<std::string> qosProfileNames() {
  return {"sensor_data", "state", "map", "command", "bulk_transfer", "viewing", "latched_state"};
}

QosProfile qosProfileByName(const std::string& name) {
  if (name == "sensor_data") return sensorDataQos();
  if (name == "state") return stateQos();
  if (name == "map") return mapQos();
  if (name == "command") return commandQos();
  if (name == "bulk_transfer") return bulkTransferQos();
  if (name == "viewing") return viewingQos();
  if (name == "latched_state") return latchedStateQos();
  std::string known;
  for (const auto& n : qosProfileNames()) known += (known.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown QoS profile '" + name + "' (known: " + known + ")");
}

}  // namespace auv::interfaces
