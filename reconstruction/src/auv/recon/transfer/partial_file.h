#pragma once
// A file being pulled: its bytes in `<final>.part` and a progress record
// `<final>.part.progress` naming which chunks are on disk and their SHA-256. Chunks already on
// disk are never fetched again; when a pull resumes, every recorded chunk is re-read and
// checked against its digest (no network), and only chunks that fail are fetched again. The
// final name appears only after the whole file's SHA-256 matched the vehicle's (rename).
//
// Progress record (text, append-only, so an interruption loses at most the last line):
//   auv-pull-progress 1
//   file <path relative to the recorder root>
//   size <bytes>
//   sha256 <whole file, as the vehicle catalogued it>
//   chunk_bytes <bytes per chunk; the last chunk is shorter>
//   chunk <index> <sha256 of that chunk>      (one line per chunk on disk, any order)

#include <cstdint>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "auv/transfer/sha256.h"

namespace auv::recon::transfer {

/// A file as the vehicle's catalogue describes it.
struct RemoteFile {
  std::string path;  ///< relative to the recorder root, e.g. "left/left_0001.mp4"
  uint64_t size = 0;
  std::string sha256;
};

/// The whole file's digest did not match: the partial file was discarded.
class VerifyError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class PartialFile {
 public:
  /// Opens (resuming when the record describes the same remote file) or creates the partial
  /// file for `remote`; `chunk_bytes` applies to a new record only. A record for another
  /// version of the file, or one that cannot be parsed, is replaced (see startNote()).
  /// Throws std::runtime_error naming the file on I/O errors.
  PartialFile(std::filesystem::path final_path, RemoteFile remote, uint32_t chunk_bytes);
  ~PartialFile();
  PartialFile(const PartialFile&) = delete;
  PartialFile& operator=(const PartialFile&) = delete;

  static std::filesystem::path partPath(const std::filesystem::path& final_path);
  static std::filesystem::path progressPath(const std::filesystem::path& final_path);

  const RemoteFile& remote() const { return remote_; }
  const std::filesystem::path& finalPath() const { return final_path_; }
  uint32_t chunkBytes() const { return chunk_bytes_; }
  size_t chunkCount() const { return have_.size(); }
  uint64_t chunkOffset(size_t index) const { return uint64_t{chunk_bytes_} * index; }
  uint32_t chunkLength(size_t index) const;
  bool has(size_t index) const { return have_[index]; }
  uint64_t missingBytes() const;
  bool allChunks() const { return missing_chunks_ == 0; }
  /// Chunks found on disk and re-verified when the record was opened.
  size_t reusedChunks() const { return reused_chunks_; }
  /// Recorded chunks whose bytes on disk no longer matched their digest (fetched again).
  size_t droppedChunks() const { return dropped_chunks_; }
  /// Why an existing record was not used (empty when resumed or new).
  const std::string& startNote() const { return start_note_; }

  /// Writes chunk `index` (its full length) and records `sha256` as its digest: the digest the
  /// vehicle sent with it, checked by finish() (or computed here by the caller).
  void writeChunk(size_t index, const uint8_t* data, size_t size, const std::string& sha256);
  /// With every chunk on disk: checks the whole file's SHA-256, then renames it to the final
  /// name, removes the record and returns an empty list. The digest covers the bytes as
  /// written (chunks arriving in order are hashed as they are written, the rest is read back
  /// here), so a pull in order needs no second pass. On a mismatch every chunk is checked
  /// against its recorded digest: the ones that fail are dropped and returned, to be fetched
  /// again; if none fails (the vehicle's digests disagree with each other), the partial file
  /// is discarded and VerifyError thrown.
  std::vector<size_t> finish();
  /// Removes the partial file and its record.
  void discard();

 private:
  void startFresh();
  bool loadRecord();
  void appendRecord(const std::string& line);
  /// Feeds the whole-file digest with the chunks on disk from hashed_to_ onwards.
  void advanceWholeDigest(const uint8_t* written, size_t index);

  std::filesystem::path final_path_;
  RemoteFile remote_;
  uint32_t chunk_bytes_;
  std::vector<bool> have_;
  std::vector<std::string> digests_;  // recorded digest per chunk on disk
  size_t missing_chunks_ = 0;
  size_t reused_chunks_ = 0;
  size_t dropped_chunks_ = 0;
  std::string start_note_;
  int fd_ = -1;         // the .part file
  int record_fd_ = -1;  // the progress record, opened for appending
  // SHA-256 of bytes [0, hashed_to_) of the .part, fed as chunks are written in order.
  std::unique_ptr<auv::transfer::Sha256> whole_;
  uint64_t hashed_to_ = 0;
};

}  // namespace auv::recon::transfer
