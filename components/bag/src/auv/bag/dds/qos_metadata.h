#pragma once
// The QoS a topic was offered with, kept in its MCAP channel's metadata so that `auv bag play`
// offers the same again (a transient-local map stays transient local, a best-effort stream
// best effort). Keys (components/bag/README.md, "Channels"):
//
//   qos.reliability  reliable | best_effort
//   qos.durability   volatile | transient_local
//   qos.history      keep_last | keep_all
//   qos.depth        the writers' largest announced depth (keep_last)
//   qos.deadline_s, qos.liveliness, qos.liveliness_lease_s   the strictest any writer offered
//                    (readers that request a deadline match only offers at least as strict)
//   offered_qos_profiles  one line per writer, for people (QosProfile::summary())
//   dds_type         the DDS type name as announced ("auv::msg::Odometry")
//   writers          the writers' vendors ("cyclonedds", "fastdds")

#include <string>
#include <vector>

#include "auv/bag/records.h"
#include "auv/interfaces/graph.h"
#include "auv/interfaces/qos.h"

namespace auv::bag {

/// What a recorder writes for a topic: the writers' QoS (as discovered) and their vendors.
StringMap channelMetadata(const std::string& dds_type,
                          const std::vector<interfaces::EndpointInfo>& writers,
                          const interfaces::QosProfile& recorded_with);

/// The QoS to play a channel with: what `channelMetadata` wrote; a key that is missing (a bag
/// of another recorder) keeps `fallback`'s value. Throws std::invalid_argument naming the key
/// and value when one is not understood.
interfaces::QosProfile qosFromMetadata(const StringMap& metadata,
                                       const interfaces::QosProfile& fallback);

}  // namespace auv::bag
