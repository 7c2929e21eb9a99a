#pragma once
// Pulls a vehicle's recordings into `<survey>/recordings/<camera>/` over the recorder's
// services (the transfer protocol, components/transfer/README.md; the vehicle's side is
// components/recorder): waits for the vehicle, lists its catalogue, and fetches what
// is not verified on disk yet, several chunks in flight. Resumable (PartialFile), verified
// (per-chunk digest on the wire, whole-file SHA-256 before the rename, Manifest), and it gives
// up with VEHICLE_LOST when the vehicle stays silent for `timeout_s`; a vehicle that restarts
// within that time is picked up again.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "auv/interfaces/node.h"

namespace auv::recon::transfer {

struct PullOptions {
  std::string vehicle = "auv";       ///< the recorder's vehicle_name
  std::filesystem::path survey;      ///< survey folder; files go to <survey>/recordings/
  double timeout_s = 60.0;           ///< s: wait for the vehicle to appear / answer again
  int in_flight = 8;                 ///< chunk requests outstanding at once
  uint32_t chunk_bytes = 1u << 20;   ///< bytes per chunk (capped by the recorder's maximum)
  std::vector<std::string> cameras;  ///< only these cameras; empty = all
  double progress_period_s = 0.1;    ///< s between progress callbacks (0: after every chunk)
  /// Throws std::invalid_argument naming the option.
  void check() const;
};

/// What the display shows.
struct PullProgress {
  uint64_t bytes_total = 0;  ///< bytes to fetch in this run so far (grows as recordings appear)
  uint64_t bytes_done = 0;   ///< of those, on disk
  std::string current_file;  ///< last file a chunk arrived for
  std::string waiting;       ///< non-empty while waiting for the vehicle: why
};

struct PullStats {
  size_t recordings_on_vehicle = 0;     ///< complete recordings listed (after --camera)
  size_t recordings_pulled = 0;         ///< verified in this run
  size_t recordings_present = 0;        ///< already verified on disk
  size_t recordings_failed = 0;         ///< reported in `problems`
  size_t recordings_being_written = 0;  ///< incomplete on the vehicle, not pulled
  size_t files_pulled = 0;              ///< recordings + sidecars renamed into place
  uint64_t bytes_missing = 0;           ///< bytes not on disk when their files were opened
  uint64_t bytes_requested = 0;         ///< bytes asked for (every request, repeats included)
  uint64_t bytes_received = 0;          ///< data bytes received (corrupted chunks included)
  size_t chunks_reused = 0;             ///< found on disk and re-verified on resume
  size_t chunks_dropped = 0;            ///< on disk but failing their digest: fetched again
  size_t chunks_corrupted = 0;          ///< arrived not matching data_sha256: fetched again
  size_t requests_timed_out = 0;        ///< unanswered, asked again
  size_t vehicle_restarts = 0;          ///< times the recorder vanished and came back
  double seconds = 0;
  std::vector<std::string> problems;  ///< one line per failed recording
  std::string lost;                   ///< why the vehicle was given up (VEHICLE_LOST)
};

enum class PullResult { COMPLETE, FAILED_FILES, VEHICLE_LOST, INTERRUPTED };

class Puller {
 public:
  using ProgressCallback = std::function<void(const PullProgress&)>;
  using MessageCallback = std::function<void(const std::string&)>;

  /// Creates the recorder clients on `node` (replies are handled in DDS threads: the node
  /// needs no executor). check()s the options.
  Puller(interfaces::Node& node, PullOptions options);
  ~Puller();

  /// Called from run()'s thread at most every `progress_period_s`.
  void onProgress(ProgressCallback callback) { on_progress_ = std::move(callback); }
  /// Notes worth a line of their own (resumed files, refetched chunks, problems).
  void onMessage(MessageCallback callback) { on_message_ = std::move(callback); }

  /// True once the vehicle's recorder services are matched (run() waits for this itself).
  bool vehicleReady() const;

  /// Pulls until every complete recording is verified on disk (or failed), the vehicle is
  /// lost, or stop(): one PullSession (pull_session.h) on the locked survey. Throws
  /// std::runtime_error for local problems (survey not writable, manifest unreadable, another pull
  /// running on the survey).
  PullResult run();
  /// Makes run() return INTERRUPTED soon, partial files kept for a resume. Any thread.
  void stop() { stop_ = true; }

  const PullStats& stats() const { return stats_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  PullOptions options_;
  PullStats stats_;
  ProgressCallback on_progress_;
  MessageCallback on_message_;
  std::atomic<bool> stop_{false};
};

}  // namespace auv::recon::transfer
