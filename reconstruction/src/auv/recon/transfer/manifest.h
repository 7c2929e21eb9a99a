#pragma once
// `<survey>/recordings/manifest.json`: what `auv recon pull` verified. Rewritten atomically
// (temporary file + rename) after each verified recording, so it always names only files
// that are on disk under their final names with the digests given. Format:
//   {
//     "format": "auv-recordings-manifest 1",
//     "recordings": [
//       {"file": "left/left_0001.mp4", "camera": "left", "vehicle": "auv",
//        "size_bytes": 123, "sha256": "<64 hex>",
//        "sidecar_file": "left/left_0001.mp4.frames.csv", "sidecar_size_bytes": 45,
//        "sidecar_sha256": "<64 hex>", "frame_count": 600,
//        "start_time_s": 10.0, "end_time_s": 69.9, "time_synchronised": false,
//        "verified_at": "2025-01-31T12:00:00Z"}, ...]
//   }
// Paths are relative to `<survey>/recordings/`; sidecar fields are empty/0 without a sidecar.

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>

namespace auv::recon::transfer {

struct ManifestEntry {
  std::string file;
  std::string camera;
  std::string vehicle;
  uint64_t size_bytes = 0;
  std::string sha256;
  std::string sidecar_file;
  uint64_t sidecar_size_bytes = 0;
  std::string sidecar_sha256;
  uint64_t frame_count = 0;
  double start_time_s = 0;
  double end_time_s = 0;
  bool time_synchronised = false;
  std::string verified_at;  ///< UTC, ISO 8601
};

class Manifest {
 public:
  /// Loads `path` if it exists; throws std::runtime_error naming the file and the field when
  /// it cannot be parsed (it is never overwritten then).
  explicit Manifest(std::filesystem::path path);

  const ManifestEntry* find(const std::string& file) const;
  /// Adds or replaces the entry and rewrites the file atomically.
  void record(ManifestEntry entry);
  const std::map<std::string, ManifestEntry>& entries() const { return entries_; }
  const std::filesystem::path& path() const { return path_; }

 private:
  void save() const;

  std::filesystem::path path_;
  std::map<std::string, ManifestEntry> entries_;  // by file
};

/// Now as "YYYY-MM-DDTHH:MM:SSZ".
std::string utcNow();

}  // namespace auv::recon::transfer
