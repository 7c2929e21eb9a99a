#include "auv/bag/dds/qos_metadata.h"

#include "auv/config/yaml_scalars.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>

namespace auv::bag {

using interfaces::Durability;
using interfaces::History;
using interfaces::QosProfile;
using interfaces::Reliability;

namespace {

std::string number(double value) {
  std::ostringstream out;
  out.precision(17);
  out << value;
  return out.str();
}

}  // namespace

StringMap channelMetadata(const std::string& dds_type,
                          const std::vector<interfaces::EndpointInfo>& writers,
                          const QosProfile& recorded_with) {
  // The writers decide what a player should offer: reliable and transient local when every
  // writer was (what the recorder's compatible reader asked for too), and the history the
  // writers announced (Fast DDS writers announce none: then the key is left out).
  QosProfile offered = recorded_with;
  int depth = 0;
  bool keep_all = false;
  // Readers may request a deadline or a liveliness lease (vehicle state asks for 0.5 s): an
  // offer matches them only if it is at least as strict, so a player offers the strictest
  // any writer did.
  double deadline_s = 0, lease_s = 0;
  bool manual_liveliness = false;
  std::string profiles;
  std::set<std::string> vendors;
  for (const auto& writer : writers) {
    if (writer.history_known) {
      keep_all = keep_all || writer.qos.history == History::KEEP_ALL;
      depth = std::max(depth, writer.qos.depth);
    }
    const auto strictest = [](double current, double offered) {
      return offered > 0 && (current == 0 || offered < current) ? offered : current;
    };
    deadline_s = strictest(deadline_s, writer.qos.deadline_s);
    lease_s = strictest(lease_s, writer.qos.liveliness_lease_s);
    manual_liveliness =
        manual_liveliness || writer.qos.liveliness == interfaces::Liveliness::MANUAL_BY_TOPIC;
    // A Fast DDS writer announces no history: its summary would show the default.
    std::string summary = writer.qos.summary();
    const size_t history = summary.find("keep_");
    if (!writer.history_known && history != std::string::npos)
      summary.replace(history, summary.find(',', history) - history, "history not announced");
    profiles += (profiles.empty() ? "" : "\n") + summary;
    vendors.insert(interfaces::vendorNameFromGuid(writer.guid));
  }
  std::string vendor_list;
  for (const auto& vendor : vendors) vendor_list += (vendor_list.empty() ? "" : ",") + vendor;
  StringMap metadata = {
      {"dds_type", dds_type},
      {"qos.reliability",
       offered.reliability == Reliability::RELIABLE ? "reliable" : "best_effort"},
      {"qos.durability",
       offered.durability == Durability::TRANSIENT_LOCAL ? "transient_local" : "volatile"},
      {"offered_qos_profiles", profiles},
      {"writers", vendor_list},
  };
  if (deadline_s > 0) metadata["qos.deadline_s"] = number(deadline_s);
  if (lease_s > 0) metadata["qos.liveliness_lease_s"] = number(lease_s);
  if (manual_liveliness) metadata["qos.liveliness"] = "manual_by_topic";
  if (keep_all) {
    metadata["qos.history"] = "keep_all";
  } else if (depth > 0) {
    metadata["qos.history"] = "keep_last";
    metadata["qos.depth"] = std::to_string(depth);
  }
  return metadata;
}

namespace {

const std::string* find(const StringMap& metadata, const std::string& key) {
  const auto it = metadata.find(key);
  return it == metadata.end() ? nullptr : &it->second;
}

[[noreturn]] void refuse(const std::string& key, const std::string& value,
                         const std::string& expected) {
  throw std::invalid_argument("channel metadata " + key + ": expected " + expected + ", got '" +
                              value + "'");
}

}  // namespace

QosProfile qosFromMetadata(const StringMap& metadata, const QosProfile& fallback) {
  QosProfile qos = fallback;
  if (const auto* value = find(metadata, "qos.reliability")) {
    if (*value != "reliable" && *value != "best_effort")
      refuse("qos.reliability", *value, "reliable or best_effort");
    qos.reliability = *value == "reliable" ? Reliability::RELIABLE : Reliability::BEST_EFFORT;
  }
  if (const auto* value = find(metadata, "qos.durability")) {
    if (*value != "volatile" && *value != "transient_local")
      refuse("qos.durability", *value, "volatile or transient_local");
    qos.durability =
        *value == "transient_local" ? Durability::TRANSIENT_LOCAL : Durability::VOLATILE;
  }
  if (const auto* value = find(metadata, "qos.history")) {
    if (*value != "keep_last" && *value != "keep_all")
      refuse("qos.history", *value, "keep_last or keep_all");
    qos.history = *value == "keep_all" ? History::KEEP_ALL : History::KEEP_LAST;
  }
  if (const auto* value = find(metadata, "qos.depth")) {
    size_t used = 0;
    int depth = 0;
    try {
      depth = std::stoi(*value, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != value->size() || depth < 1) refuse("qos.depth", *value, "an integer >= 1");
    qos.depth = depth;
  }
  const auto seconds = [&](const char* key, double& into) {
    const auto* value = find(metadata, key);
    if (!value) return;
    const auto parsed = config::parseNumber(*value);
    if (!parsed || !(*parsed > 0) || !std::isfinite(*parsed)) refuse(key, *value, "seconds > 0");
    into = *parsed;
  };
  seconds("qos.deadline_s", qos.deadline_s);
  seconds("qos.liveliness_lease_s", qos.liveliness_lease_s);
  if (const auto* value = find(metadata, "qos.liveliness")) {
    if (*value != "automatic" && *value != "manual_by_topic")
      refuse("qos.liveliness", *value, "automatic or manual_by_topic");
    qos.liveliness = *value == "manual_by_topic" ? interfaces::Liveliness::MANUAL_BY_TOPIC
                                                 : interfaces::Liveliness::AUTOMATIC;
  }
  // A best-effort transient-local offer is refused by check(); such a bag was not ours.
  if (qos.reliability == Reliability::BEST_EFFORT) qos.durability = Durability::VOLATILE;
  return qos;
}

}  // namespace auv::bag
