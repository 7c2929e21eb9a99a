#pragma once
// The transfer protocol's DDS names, per vehicle: `<vehicle>/recorder/...`, so the recorders of
// several vehicles share a domain without colliding; the chunk size limits both sides agree on.
// Used by the vehicle's recorder component and by the shore's `auv recon pull`
// (components/transfer/README.md).

#include <cctype>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace auv::transfer {

/// Default cap of one FileChunkReply's data (parameter max_chunk_bytes): 1 MiB samples
/// cross both vendors reliably and amortise the per-request cost (docs/performance.md).
inline constexpr uint32_t kDefaultMaxChunkBytes = 1u << 20;
/// Largest cap accepted: 16 MiB samples still cross, but gain nothing and cost memory.
inline constexpr uint32_t kLargestMaxChunkBytes = 16u << 20;

/// Throws std::invalid_argument unless `name` is a letter followed by letters, digits, '_'.
inline void checkVehicleName(const std::string& name) {
  bool ok = !name.empty() && name.size() <= 64 && std::isalpha(static_cast<unsigned char>(name[0]));
  for (char c : name) ok = ok && (std::isalnum(static_cast<unsigned char>(c)) || c == '_');
  if (!ok) {
    throw std::invalid_argument("vehicle name '" + name +
                                "': use a letter, then letters, digits or '_' (at most 64)");
  }
}

inline std::string listRecordingsService(const std::string& vehicle) {
  return vehicle + "/recorder/list_recordings";
}
inline std::string fetchChunkService(const std::string& vehicle) {
  return vehicle + "/recorder/fetch_chunk";
}
inline std::string recordingsTopic(const std::string& vehicle) {
  return vehicle + "/recorder/recordings";
}

}  // namespace auv::transfer
