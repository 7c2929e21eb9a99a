#pragma once
// How this layer configures Cyclone DDS; shared by the backend and the graph inspector.

namespace auv::interfaces::detail {

/// Creates the Cyclone domain `domain_id` bound to loopback, unless CYCLONEDDS_URI is set
/// (then Cyclone reads the user's configuration). With AUV_SECURITY_* set, the configuration
/// also carries that identity's <Security> element (docs/security.md). Idempotent; call
/// before creating a participant on that domain.
void ensureCycloneDomain(int domain_id);

}  // namespace auv::interfaces::detail
