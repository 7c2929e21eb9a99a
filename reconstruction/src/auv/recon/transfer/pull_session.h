#pragma once
// One run of Puller::run() (puller.h; pull_session.cc, fetching in pull_session_fetch.cc), in
// rounds: wait for the vehicle and list its catalogue, decide what to fetch (resuming partial
// files), fetch with several chunks in flight, verify, rename and record in the manifest; again
// while the vehicle is still cataloguing or the round fetched something. The protocol (names,
// digests, path checks) is components/transfer's.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <future>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "auv/interfaces/node.h"
#include "auv/recon/transfer/manifest.h"
#include "auv/recon/transfer/partial_file.h"
#include "auv/recon/transfer/puller.h"

namespace auv::recon::transfer {

using ListClient = interfaces::Client<msg::RecordingCatalogueRequest, msg::RecordingCatalogueReply>;
using FetchClient = interfaces::Client<msg::FileChunkRequest, msg::FileChunkReply>;

/// What the Puller lends one session: its options, clients, callbacks, stop flag and stats.
struct PullContext {
  const PullOptions& options;
  ListClient& list;
  FetchClient& fetch;
  int domain_id = 0;
  const Puller::ProgressCallback& on_progress;
  const Puller::MessageCallback& on_message;
  const std::atomic<bool>& stop;
  PullStats& stats;
};

class PullSession {
 public:
  using Clock = std::chrono::steady_clock;

  /// `recordings` is `<survey>/recordings/` (created and locked by the caller), `manifest`
  /// its manifest.json; `start` is when the pull began (stats().seconds counts from it).
  PullSession(PullContext context, std::filesystem::path recordings, Manifest& manifest,
              Clock::time_point start);

  PullResult run();

 private:
  /// One recording of this round and its files (video, then sidecar).
  struct Task {
    msg::RecordingInfo info;
    size_t files_left = 0;
    bool failed = false;
  };
  /// One file being fetched.
  struct FileState {
    Task* task = nullptr;
    std::unique_ptr<PartialFile> partial;
    std::map<size_t, std::vector<uint8_t>> buffers;  // chunks partly received (short replies)
    size_t in_flight = 0;
    bool failed = false;
    bool done = false;
    std::optional<Clock::time_point> not_found_since;
    size_t corrupted = 0;  // chunks that arrived not matching their digest
  };
  /// A byte range within one chunk.
  struct Work {
    FileState* file = nullptr;
    size_t chunk = 0;
    uint64_t offset = 0;
    uint32_t length = 0;
    Clock::time_point not_before{};
  };
  struct InFlight {
    Work work;
    std::future<msg::FileChunkReply> reply;
    Clock::time_point sent;
  };
  /// What the vehicle listed in one round.
  struct Listing {
    std::vector<msg::RecordingInfo> recordings;
    uint32_t pending = 0;    // files the vehicle has not hashed yet
    uint32_t max_chunk = 0;  // ours, capped by the vehicle's max_chunk_bytes
  };
  /// One round's work; the deques keep the addresses Work and FileState point to.
  struct Round {
    std::deque<Task> tasks;
    std::deque<FileState> files;
    std::deque<Work> queue;
  };
  /// The fetch window of one round.
  struct Window {
    std::deque<InFlight> flight;
    double rate = 0;  // bytes/s, smoothed: sizes the request timeout
    Clock::time_point rate_since;
    uint64_t rate_bytes = 0;
    bool service_was_ready = false;
    // Until the recorder has answered one fetch_chunk request, its reply writer may not have
    // discovered our reader yet (discovery is asymmetric) and would drop what it writes: a
    // zero-length request goes out first with call(), repeated every 50 ms (cheap, where
    // repeating a whole chunk would send it twice on a slow link; the default 500 ms cost
    // half a second of many pulls); the chunks are pipelined with callAsync() once it is
    // answered. Again after the vehicle comes back (new writers).
    bool fetch_answered = false;
  };

  // Listing.
  std::optional<PullResult> listCatalogue(Listing& listing);
  std::optional<PullResult> requestCatalogue(const std::string& camera,
                                             msg::RecordingCatalogueReply& reply);
  void noteVehicleAnswered();
  // Deciding what to fetch.
  void planRound(const Listing& listing);
  bool noteIncomplete(const msg::RecordingInfo& info);
  bool acceptEntry(const msg::RecordingInfo& info);
  bool verifiedBefore(const msg::RecordingInfo& info) const;
  void addTask(const msg::RecordingInfo& info, uint32_t chunk_bytes);
  void checkOnDisk(Task& task, const RemoteFile& remote, const std::filesystem::path& final_path);
  void openFile(Task& task, const RemoteFile& remote, const std::filesystem::path& final_path,
                uint32_t chunk_bytes);
  void finishReadyFiles();
  // Fetching.
  std::optional<PullResult> fetchAll(uint32_t max_chunk);
  void noticeVehicleChange(bool ready);
  size_t windowSize() const;
  void fillWindow();
  bool probeReplyPath(const msg::FileChunkRequest& request);
  void collectReplies(uint32_t max_chunk);
  void handleReply(Work work, const msg::FileChunkReply& reply);
  void retryLater(FileState& file, Work work, const msg::FileChunkReply& reply);
  void countReceived(size_t bytes);
  bool replyMatches(FileState& file, const Work& work, const msg::FileChunkReply& reply);
  void handleCorrupted(FileState& file, const Work& work);
  bool storePiece(FileState& file, const Work& work, const std::vector<uint8_t>& data);
  // Finishing.
  void finishIfComplete(FileState& file);
  void refetchChunks(FileState& file, const std::vector<size_t>& bad);
  void recordIfDone(Task& task);
  void failFile(FileState& file, const std::string& why);
  void countRecordings(const Listing& listing);
  void waitForCataloguing(uint32_t pending);
  // Reporting and ending.
  static double secondsSince(Clock::time_point t);
  void report(bool force);
  void message(const std::string& text);
  PullResult interrupted();
  PullResult lost(const std::string& what);
  std::string waitingForVehicle() const;

  /// A link that corrupts this many chunks of one file is not worth retrying.
  static constexpr size_t kMaxCorruptedChunksPerFile = 16;

  PullContext context_;
  const PullOptions& options_;
  PullStats& stats_;
  std::filesystem::path recordings_;
  Manifest& manifest_;
  Clock::time_point start_;
  std::chrono::duration<double> timeout_;

  PullProgress progress_;
  Clock::time_point last_progress_call_;
  Clock::time_point last_alive_;
  std::set<std::string> failed_files_;  // "<path> <sha256>": not tried again in later rounds
  std::set<std::string> reported_;      // recordings with a problem line already
  bool was_ready_ = false;

  Round round_;
  Window window_;
};

}  // namespace auv::recon::transfer
