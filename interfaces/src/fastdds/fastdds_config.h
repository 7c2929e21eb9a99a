#pragma once
// How this layer configures Fast DDS; shared by the backend and the graph inspector.

#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>

#include "auv/interfaces/backend.h"

namespace auv::interfaces::detail {

/// Participant QoS: the user's XML profiles when FASTRTPS_DEFAULT_PROFILES_FILE is set,
/// otherwise one UDPv4 transport on 127.0.0.1 only. Carries the node name and the
/// USER_DATA identity of participantUserData().
eprosima::fastdds::dds::DomainParticipantQos fastddsParticipantQos(
    const ParticipantOptions& options);

}  // namespace auv::interfaces::detail
