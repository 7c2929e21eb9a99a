#pragma once
// What `auv bag info` shows of a bag: its channels and their message counts, times,
// compression, chunks, size and any damage — from the summary when the file has an intact
// one (fast: no message is read), else from the linear scan that recovers it.

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "auv/bag/mcap_reader.h"

namespace auv::bag {

struct ChannelSummary {
  uint16_t id = 0;
  std::string topic;
  std::string schema_name;       ///< "" when the channel has no schema
  std::string schema_encoding;   ///< e.g. "omgidl"
  std::string message_encoding;  ///< e.g. "cdr"
  uint64_t message_count = 0;
  StringMap metadata;  ///< e.g. the QoS the topic was offered with
};

struct Summary {
  std::string path;
  uint64_t file_size = 0;  ///< bytes
  std::string profile;
  std::string library;
  bool indexed = false;   ///< read through the summary (else: a linear scan)
  bool verified = false;  ///< every chunk and the data section CRC were checked
  uint64_t message_count = 0;
  uint64_t start_ns = 0;  ///< first log time (0 without messages)
  uint64_t end_ns = 0;    ///< last log time
  double duration_s = 0.0;
  std::vector<ChannelSummary> channels;  ///< by channel id
  uint64_t chunk_count = 0;
  uint64_t damaged_chunks = 0;                         ///< of those found damaged
  std::map<std::string, uint64_t> chunk_compressions;  ///< "zstd" -> chunks ("none" for "")
  uint64_t compressed_bytes = 0;                       ///< chunk records as stored
  uint64_t uncompressed_bytes = 0;                     ///< chunk records uncompressed
  std::vector<std::string> metadata_names;
  uint32_t attachment_count = 0;
  std::vector<Damage> damage;
};

/// The summary of the bag at `path`; `verify` also reads every chunk and checks its CRC and
/// the data section's (slower: it reads the whole file). Throws BagError for a file that
/// cannot be opened or is not MCAP; damage is in the result.
Summary info(const std::filesystem::path& path, bool verify = false);

/// The summary as `auv bag info` prints it (like `mcap info` and `ros2 bag info`).
std::string formatInfo(const Summary& summary);

/// "2026-11-27 10:00:00.123456789 UTC", or a plain count of seconds for times before 2000
/// (clocks since boot, simulated time).
std::string formatTime(uint64_t ns);

/// "1.5 KiB", "12.3 MiB".
std::string formatBytes(uint64_t bytes);

}  // namespace auv::bag
