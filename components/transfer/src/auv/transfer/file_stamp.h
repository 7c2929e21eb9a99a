#pragma once
// What identifies one state of a file on disk (size and modification time): the vehicle
// catalogues a file in one state and serves its bytes only while the file is still in it.

#include <cstdint>
#include <filesystem>
#include <optional>

namespace auv::transfer {

/// Changed size or mtime = changed file.
struct FileStamp {
  uint64_t size = 0;
  int64_t mtime_ns = 0;
  bool operator==(const FileStamp& other) const {
    return size == other.size && mtime_ns == other.mtime_ns;
  }
  bool operator!=(const FileStamp& other) const { return !(*this == other); }
};

/// Stamp of a regular file; nullopt if it does not exist or is not a regular file (symlinks
/// are not followed).
std::optional<FileStamp> stampOf(const std::filesystem::path& path);

}  // namespace auv::transfer
