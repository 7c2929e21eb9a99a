#pragma once
// The catalogue of a recordings root, without DDS: what the recorder component serves.
//
// Layout (the camera drivers' and the simulator's, components/recorder/README.md):
//   <root>/<camera>/<name>.mp4                 closed recording
//   <root>/<camera>/<name>.mp4.frames.csv      its sidecar: frame,camera_time_s[,...]
//   <root>/<camera>/<name>.incomplete.mp4      being written (renamed when closed)
//   <root>/<camera>/<name>.mp4.frames.csv.incomplete
//
// scan() brings the catalogue up to date. Each closed file (and sidecar) is hashed once,
// remembered with its size and modification time; a later scan that finds another size or
// time hashes it again, and if the content differs the recording is no longer `complete`
// (its `problem` says what changed), so the old digest is never served for new bytes.

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "auv/transfer/file_stamp.h"
#include "auv/transfer/sha256.h"

namespace auv::recorder {

// The protocol's pieces the catalogue is made of (components/transfer).
using transfer::FileStamp;
using transfer::Sha256;
using transfer::stampOf;

struct CatalogueOptions {
  std::filesystem::path root;                      ///< recordings root
  std::vector<std::string> extensions = {".mp4"};  ///< recording file endings, with the dot
  /// B, grid of the chunk digests kept for each complete recording (computed in the same read
  /// as its SHA-256, so serving a chunk on that grid needs no hashing); 0 = none.
  uint32_t chunk_digest_bytes = 0;
  /// Throws std::invalid_argument naming the field (empty root, extension without dot, ...).
  void check() const;
};

/// One recording, as the catalogue knows it (mirrors msg::RecordingInfo).
struct Recording {
  std::string camera_id;
  std::string file_path;     ///< final name relative to the root, '/'-separated
  std::string sidecar_file;  ///< final sidecar name relative to the root; empty if none
  uint64_t size_bytes = 0;
  std::string sha256;       ///< empty unless complete
  double start_time_s = 0;  ///< camera clock of the first frame (sidecar)
  double end_time_s = 0;    ///< camera clock of the last frame so far
  uint64_t frame_count = 0;
  uint64_t sidecar_size_bytes = 0;
  std::string sidecar_sha256;  ///< empty unless complete
  bool complete = false;
  /// Empty while a file is merely being written; else why it is not complete (changed after
  /// it was catalogued, unreadable) or why its metadata is partial (bad sidecar).
  std::string problem;

  // Bookkeeping: what was hashed, and where the bytes are now.
  std::string disk_path;          ///< current name relative to the root (differs while incomplete)
  std::string sidecar_disk_path;  ///< current sidecar name relative to the root
  FileStamp stamp;                ///< of the file when sha256 was computed
  FileStamp sidecar_stamp;        ///< of the sidecar when sidecar_sha256 was computed
  std::string catalogued_sha256;  ///< digest when first catalogued complete
  std::string catalogued_sidecar_sha256;  ///< sidecar digest then (changes compare to both)
  uint64_t catalogued_size = 0;           ///< size then
  bool changed = false;                   ///< changed after being catalogued complete
  /// SHA-256 of each CatalogueOptions::chunk_digest_bytes piece of the file in `stamp`'s
  /// state (shared: entries are copied by list() and scan()); null when not kept.
  std::shared_ptr<const std::vector<Sha256::Digest>> chunk_digests;
};

/// A closed file the chunk server may read, and the state it was catalogued in.
struct ServedFile {
  std::string relative_path;  ///< as on disk, relative to the root
  FileStamp stamp;
};

struct ScanReport {
  size_t hashed = 0;                  ///< files (recordings + sidecars) hashed in this scan
  std::vector<std::string> messages;  ///< what changed, for the log (one line each)
  bool modified = false;              ///< the catalogue changed (publish it)
};

class Catalogue {
 public:
  explicit Catalogue(CatalogueOptions options);  // check()s

  /// Walks the root and updates the catalogue; hashes what is new or changed. One scan at a
  /// time (callers are serialised); list() and friends may run meanwhile and see each file
  /// as soon as it is hashed. Errors of single files go into the report, never throw.
  ScanReport scan();

  /// Recordings of `camera_id` (empty: all) ordered by camera, start time, path.
  std::vector<Recording> list(const std::string& camera_id, bool include_incomplete) const;
  /// True if `camera_id` has a folder (or recordings) in the catalogue.
  bool hasCamera(const std::string& camera_id) const;
  /// Closed files found by the current/last scan but not hashed yet.
  size_t pendingFiles() const;
  /// pendingFiles() plus the closed files that appeared or changed on disk since the last scan
  /// walked the root (a cheap walk, no hashing). Answers "is the catalogue behind the disk?"
  /// at the moment of asking, so that a pull right after a recording closes waits for it
  /// instead of finishing before the next periodic scan.
  size_t pendingNow() const;
  /// +1 whenever the catalogue changes.
  uint64_t generation() const;
  /// True once a scan has walked the root (before that, an empty list means "not yet known").
  bool walked() const;

  /// The complete recording or sidecar called `file_path` (final name); nullopt otherwise.
  std::optional<ServedFile> servedFile(const std::string& file_path) const;
  /// The SHA-256 (hex) of the bytes [offset, offset + length) of the complete recording
  /// `file_path` in the state `stamp`, if that range is one piece of the chunk-digest grid
  /// (CatalogueOptions::chunk_digest_bytes; the last piece of a file may be shorter); nullopt
  /// otherwise (other ranges, sidecars, another state of the file, digests not kept).
  std::optional<std::string> chunkDigest(const std::string& file_path, const FileStamp& stamp,
                                         uint64_t offset, uint64_t length) const;
  /// The chunk server found `file_path` changed on disk: it stops being complete until a scan
  /// shows it unchanged again.
  void reportChanged(const std::string& file_path, const std::string& why);
  /// Why `file_path` (a recording or its sidecar) is no longer served, if it changed after
  /// being catalogued complete; nullopt otherwise.
  std::optional<std::string> changedProblem(const std::string& file_path) const;

  const CatalogueOptions& options() const { return options_; }

 private:
  struct Found {  // one recording found on disk by a walk
    std::string camera_id;
    std::string file_path;  // final name
    std::string disk_path;  // current name
    bool closed = false;
    FileStamp stamp;
    std::string sidecar_disk_path;  // empty: none
    bool sidecar_closed = false;
    FileStamp sidecar_stamp;
    bool closedWithSidecar() const {
      return closed && (sidecar_disk_path.empty() || sidecar_closed);
    }
    bool sameState(const Found& other) const {
      return disk_path == other.disk_path && stamp == other.stamp &&
             sidecar_disk_path == other.sidecar_disk_path && sidecar_stamp == other.sidecar_stamp;
    }
  };
  std::map<std::string, Found> walk(ScanReport& report) const;
  /// Hashes what needs it and returns the new entry (no lock held).
  Recording refresh(const Found& found, const std::optional<Recording>& known,
                    ScanReport& report) const;

  CatalogueOptions options_;
  std::mutex scan_mutex_;                        // one scan at a time
  mutable std::mutex mutex_;                     // guards the members below
  std::map<std::string, Recording> recordings_;  // by file_path
  std::vector<std::string> cameras_;
  size_t pending_ = 0;
  std::map<std::string, Found> last_walk_;  // what the last scan found, by file_path
  uint64_t generation_ = 0;
  bool walked_ = false;
};

/// What a frames sidecar says.
struct SidecarSummary {
  uint64_t frames = 0;
  double first_camera_time_s = 0;
  double last_camera_time_s = 0;
};

/// Reads a frames sidecar (header `frame,camera_time_s,...`). `partial`: the file is still
/// being written, so an unterminated last line is ignored. Throws std::runtime_error naming
/// the file and line.
SidecarSummary readSidecarSummary(const std::filesystem::path& path, bool partial);

}  // namespace auv::recorder
