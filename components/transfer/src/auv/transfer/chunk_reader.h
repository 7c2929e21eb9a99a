#pragma once
// Reads byte ranges of files under the recordings root for `fetch_chunk`. Paths come from
// the network, so every one is checked: relative, '/'-separated, no "." or "..", no empty
// element, and (after resolving symlinks) still inside the root.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "auv/transfer/file_stamp.h"

namespace auv::transfer {

/// Why a chunk could not be read; maps to a msg::ReplyCode in the component.
class ChunkError : public std::runtime_error {
 public:
  enum class Kind { INVALID_PATH, NOT_FOUND, BAD_RANGE, CHANGED, IO };
  ChunkError(Kind kind, const std::string& text) : runtime_error(text), kind_(kind) {}
  Kind kind() const { return kind_; }

 private:
  Kind kind_;
};

struct Chunk {
  std::vector<uint8_t> data;
  uint64_t total_size = 0;  ///< size of the file when read
};

class ChunkReader {
 public:
  /// `max_chunk_bytes` caps every read (> 0).
  ChunkReader(std::filesystem::path root, uint32_t max_chunk_bytes);

  /// `relative` as an absolute path inside the root; throws ChunkError INVALID_PATH naming
  /// the problem, NOT_FOUND if it does not exist or escapes the root through a symlink.
  std::filesystem::path resolve(const std::string& relative) const;

  /// Up to min(length, max_chunk_bytes) bytes from `offset`. With `expected`, the file must
  /// still have that size and modification time (else CHANGED): a file truncated or
  /// rewritten after it was catalogued is never served as the catalogued one.
  Chunk read(const std::string& relative, uint64_t offset, uint32_t length,
             const std::optional<FileStamp>& expected = std::nullopt) const;

  uint32_t maxChunkBytes() const { return max_chunk_bytes_; }

 private:
  std::filesystem::path root_;  // canonical when it exists
  uint32_t max_chunk_bytes_;
};

/// Throws ChunkError INVALID_PATH unless `relative` is a clean relative '/'-path.
void checkRelativePath(const std::string& relative);

}  // namespace auv::transfer
