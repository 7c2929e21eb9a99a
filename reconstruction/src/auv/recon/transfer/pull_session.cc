#include "auv/recon/transfer/pull_session.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <thread>

#include "auv/interfaces/msg_time.h"
#include "auv/transfer/chunk_reader.h"
#include "auv/transfer/names.h"
#include "auv/transfer/sha256.h"

namespace fs = std::filesystem;
using namespace std::chrono_literals;

namespace auv::recon::transfer {
namespace {

double toSeconds(const msg::Time& t) { return interfaces::toNanoseconds(t) * 1e-9; }

}  // namespace

double PullSession::secondsSince(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

PullSession::PullSession(PullContext context, fs::path recordings, Manifest& manifest,
                         Clock::time_point start)
    : context_(context),
      options_(context.options),
      stats_(context.stats),
      recordings_(std::move(recordings)),
      manifest_(manifest),
      start_(start),
      timeout_(options_.timeout_s),
      last_progress_call_(Clock::now() - 1s),
      last_alive_(Clock::now()) {}

PullResult PullSession::run() {
  for (;;) {  // rounds: list, pull what is new; again while the vehicle is still hashing
    Listing listing;
    if (auto end = listCatalogue(listing)) return *end;
    planRound(listing);
    finishReadyFiles();
    if (auto end = fetchAll(listing.max_chunk)) return *end;
    for (auto& file : round_.files) finishIfComplete(file);
    report(true);
    countRecordings(listing);
    // Another round if the vehicle is still hashing, or if this one fetched something (new
    // recordings may have closed meanwhile); done when a round finds nothing new.
    if (listing.pending > 0) {
      waitForCataloguing(listing.pending);
      continue;
    }
    if (round_.tasks.empty()) break;
  }
  stats_.recordings_failed = stats_.problems.size();
  stats_.seconds = secondsSince(start_);
  return stats_.problems.empty() ? PullResult::COMPLETE : PullResult::FAILED_FILES;
}

// --- Listing: wait for the vehicle, list its catalogue (per camera with --camera).

std::optional<PullResult> PullSession::listCatalogue(Listing& listing) {
  listing.max_chunk = options_.chunk_bytes;
  const std::vector<std::string> cameras =
      options_.cameras.empty() ? std::vector<std::string>{""} : options_.cameras;
  for (const auto& camera : cameras) {
    msg::RecordingCatalogueReply reply;
    if (auto end = requestCatalogue(camera, reply)) return end;
    noteVehicleAnswered();
    if (reply.status().code() == msg::REPLY_CODE_NOT_FOUND && !camera.empty()) {
      if (reported_.insert("camera " + camera).second) {
        stats_.problems.push_back("camera '" + camera + "': " + reply.status().error_text());
      }
      continue;
    }
    if (reply.status().code() != msg::REPLY_CODE_OK) {
      throw std::runtime_error("vehicle '" + options_.vehicle +
                               "' refused the catalogue request: " + reply.status().error_text());
    }
    listing.pending += reply.pending_files();
    if (reply.max_chunk_bytes() > 0) {
      listing.max_chunk = std::min(listing.max_chunk, reply.max_chunk_bytes());
    }
    for (const auto& info : reply.recordings()) listing.recordings.push_back(info);
  }
  return std::nullopt;
}

std::optional<PullResult> PullSession::requestCatalogue(const std::string& camera,
                                                        msg::RecordingCatalogueReply& reply) {
  msg::RecordingCatalogueRequest request;
  request.camera_id(camera);
  request.include_incomplete(true);
  for (;;) {
    if (context_.stop) return interrupted();
    const auto remaining = timeout_ - (Clock::now() - last_alive_);
    if (remaining <= 0s) return lost(was_ready_ ? "did not answer" : "was not found");
    progress_.waiting = context_.list.serviceReady() ? "" : waitingForVehicle();
    report(true);
    // Short calls, so stop() and the deadline are honoured promptly.
    const auto slice = std::min<std::chrono::milliseconds>(
        2000ms, std::chrono::duration_cast<std::chrono::milliseconds>(remaining) + 1ms);
    if (context_.list.call(request, &reply, slice) == interfaces::CallStatus::OK) break;
  }
  return std::nullopt;
}

void PullSession::noteVehicleAnswered() {
  last_alive_ = Clock::now();
  if (!was_ready_) {
    message("vehicle '" + options_.vehicle + "' found");
    was_ready_ = true;
  }
  progress_.waiting.clear();
}

// --- Deciding what to fetch: tasks, partial files (resumed), the queue of chunks.

void PullSession::planRound(const Listing& listing) {
  round_ = Round{};
  size_t complete_listed = 0, being_written = 0;
  for (const auto& info : listing.recordings) {
    if (!info.complete()) {
      if (noteIncomplete(info)) ++being_written;
      continue;
    }
    ++complete_listed;
    if (!acceptEntry(info)) continue;
    if (failed_files_.count(info.file_path() + " " + info.sha256())) continue;
    if (verifiedBefore(info)) continue;
    addTask(info, listing.max_chunk);
  }
  stats_.recordings_on_vehicle = complete_listed;
  stats_.recordings_being_written = being_written;
}

/// True if the recording is merely being written; a problem is reported (or, for a copy
/// verified on shore before, noted) otherwise.
bool PullSession::noteIncomplete(const msg::RecordingInfo& info) {
  const ManifestEntry* have = manifest_.find(info.file_path());
  if (!info.problem().empty() && have == nullptr) {
    if (reported_.insert(info.file_path()).second) {
      stats_.problems.push_back(info.file_path() + ": not pulled: " + info.problem());
      message(stats_.problems.back());
    }
    return false;
  }
  if (!info.problem().empty()) {
    message(info.file_path() + ": the vehicle's copy " + info.problem() +
            "; the copy verified on shore is kept");
    return false;
  }
  return true;
}

/// Paths come from the network: they must stay inside recordings/; digests must be SHA-256.
bool PullSession::acceptEntry(const msg::RecordingInfo& info) {
  try {
    auv::transfer::checkRelativePath(info.file_path());
    if (!info.sidecar_file().empty()) auv::transfer::checkRelativePath(info.sidecar_file());
    if (!auv::transfer::isSha256Hex(info.sha256()) ||
        (!info.sidecar_file().empty() && !auv::transfer::isSha256Hex(info.sidecar_sha256()))) {
      throw std::invalid_argument("catalogue entry without a valid sha256");
    }
  } catch (const std::exception& e) {
    if (reported_.insert(info.file_path()).second) {
      stats_.problems.push_back(info.file_path() + ": not pulled: " + e.what());
    }
    return false;
  }
  return true;
}

bool PullSession::verifiedBefore(const msg::RecordingInfo& info) const {
  const ManifestEntry* have = manifest_.find(info.file_path());
  return have != nullptr && have->sha256 == info.sha256() &&
         have->sidecar_sha256 == info.sidecar_sha256() && fs::exists(recordings_ / have->file);
}

void PullSession::addTask(const msg::RecordingInfo& info, uint32_t chunk_bytes) {
  round_.tasks.push_back(Task{info});
  Task& task = round_.tasks.back();
  std::vector<RemoteFile> remote = {{info.file_path(), info.size_bytes(), info.sha256()}};
  if (!info.sidecar_file().empty()) {
    remote.push_back({info.sidecar_file(), info.sidecar_size_bytes(), info.sidecar_sha256()});
  }
  for (const auto& r : remote) {
    const fs::path final_path = recordings_ / r.path;
    if (fs::exists(final_path)) {
      checkOnDisk(task, r, final_path);
    } else {
      openFile(task, r, final_path, chunk_bytes);
    }
  }
}

/// On disk under its final name but not in the manifest (e.g. interrupted just after the
/// rename): verified by hashing, never overwritten.
void PullSession::checkOnDisk(Task& task, const RemoteFile& remote, const fs::path& final_path) {
  std::string local;
  try {
    local = auv::transfer::sha256OfFile(final_path);
  } catch (const std::exception& e) {
    local = e.what();
  }
  if (local == remote.sha256) return;
  task.failed = true;
  failed_files_.insert(task.info.file_path() + " " + task.info.sha256());
  stats_.problems.push_back(remote.path + ": " + final_path.string() +
                            " exists and differs from the vehicle's file (sha256 " +
                            remote.sha256.substr(0, 12) + "...); move it away to pull it again");
  message(stats_.problems.back());
}

void PullSession::openFile(Task& task, const RemoteFile& remote, const fs::path& final_path,
                           uint32_t chunk_bytes) {
  round_.files.emplace_back();
  FileState& file = round_.files.back();
  file.task = &task;
  file.partial = std::make_unique<PartialFile>(final_path, remote, chunk_bytes);
  const PartialFile& partial = *file.partial;
  if (!partial.startNote().empty()) message(remote.path + ": " + partial.startNote());
  if (partial.reusedChunks() > 0 || partial.droppedChunks() > 0) {
    message(remote.path + ": resumed, " + std::to_string(partial.reusedChunks()) +
            " chunks on disk re-verified" +
            (partial.droppedChunks() > 0 ? ", " + std::to_string(partial.droppedChunks()) +
                                               " failed their digest and are fetched again"
                                         : ""));
  }
  stats_.chunks_reused += partial.reusedChunks();
  stats_.chunks_dropped += partial.droppedChunks();
  const uint64_t missing = partial.missingBytes();
  stats_.bytes_missing += missing;
  progress_.bytes_total += missing;
  ++task.files_left;
  for (size_t i = 0; i < partial.chunkCount(); ++i) {
    if (!partial.has(i)) {
      round_.queue.push_back(Work{&file, i, partial.chunkOffset(i), partial.chunkLength(i)});
    }
  }
}

/// Files with nothing to fetch (all chunks re-verified on disk) finish now.
void PullSession::finishReadyFiles() {
  for (auto& file : round_.files) finishIfComplete(file);
  for (auto& task : round_.tasks) {
    if (task.files_left == 0 && !task.failed) recordIfDone(task);
  }
}

// --- Finishing: whole-file check, rename, manifest.

void PullSession::finishIfComplete(FileState& file) {
  if (file.failed || file.task->failed || file.done || !file.partial->allChunks() ||
      file.in_flight > 0) {
    return;
  }
  try {
    const std::vector<size_t> bad = file.partial->finish();
    if (!bad.empty()) {
      refetchChunks(file, bad);
      return;
    }
    file.done = true;
    ++stats_.files_pulled;
    --file.task->files_left;
    recordIfDone(*file.task);
  } catch (const VerifyError& e) {
    failFile(file, e.what());
  }
}

/// Chunks found bad by the whole-file check: fetched again, alone.
void PullSession::refetchChunks(FileState& file, const std::vector<size_t>& bad) {
  for (size_t index : bad) {
    const uint64_t offset = file.partial->chunkOffset(index);
    ++stats_.chunks_corrupted;
    ++file.corrupted;
    message(file.partial->remote().path + ": chunk at offset " + std::to_string(offset) +
            " arrived corrupted (SHA-256 mismatch); fetching it again");
    round_.queue.push_front(Work{&file, index, offset, file.partial->chunkLength(index)});
  }
  if (file.corrupted > kMaxCorruptedChunksPerFile) {
    failFile(file, std::to_string(file.corrupted) +
                       " chunks arrived corrupted (SHA-256 mismatch); giving up");
  }
}

void PullSession::recordIfDone(Task& task) {
  if (task.failed || task.files_left > 0) return;
  const msg::RecordingInfo& info = task.info;
  ManifestEntry entry;
  entry.file = info.file_path();
  entry.camera = info.camera_id();
  entry.vehicle = options_.vehicle;
  entry.size_bytes = info.size_bytes();
  entry.sha256 = info.sha256();
  entry.sidecar_file = info.sidecar_file();
  entry.sidecar_size_bytes = info.sidecar_size_bytes();
  entry.sidecar_sha256 = info.sidecar_sha256();
  entry.frame_count = info.frame_count();
  entry.start_time_s = toSeconds(info.start_time());
  entry.end_time_s = toSeconds(info.end_time());
  entry.time_synchronised = info.time_synchronised();
  entry.verified_at = utcNow();
  manifest_.record(entry);
  ++stats_.recordings_pulled;
}

/// The file's recording fails (one problem line); the file is not tried again in later rounds.
void PullSession::failFile(FileState& file, const std::string& why) {
  if (file.failed) return;
  file.failed = true;
  failed_files_.insert(file.partial->remote().path + " " + file.partial->remote().sha256);
  if (!file.task->failed) {
    file.task->failed = true;
    reported_.insert(file.task->info.file_path());
    stats_.problems.push_back(file.partial->remote().path + ": " + why);
    message(stats_.problems.back());
  }
}

void PullSession::countRecordings(const Listing& listing) {
  stats_.recordings_present = 0;
  stats_.recordings_failed = 0;
  for (const auto& info : listing.recordings) {
    if (!info.complete()) continue;
    const ManifestEntry* have = manifest_.find(info.file_path());
    if (have != nullptr && have->sha256 == info.sha256()) {
      ++stats_.recordings_present;
    } else {
      ++stats_.recordings_failed;
    }
  }
  stats_.recordings_present -= std::min(stats_.recordings_present, stats_.recordings_pulled);
}

void PullSession::waitForCataloguing(uint32_t pending) {
  progress_.waiting = "vehicle is cataloguing " + std::to_string(pending) + " files";
  report(true);
  std::this_thread::sleep_for(500ms);
}

// --- Reporting and ending.

void PullSession::report(bool force) {
  if (!context_.on_progress) return;
  if (!force && secondsSince(last_progress_call_) < options_.progress_period_s) return;
  last_progress_call_ = Clock::now();
  context_.on_progress(progress_);
}

void PullSession::message(const std::string& text) {
  if (context_.on_message) context_.on_message(text);
}

PullResult PullSession::interrupted() {
  stats_.seconds = secondsSince(start_);
  return PullResult::INTERRUPTED;
}

PullResult PullSession::lost(const std::string& what) {
  stats_.lost = "vehicle '" + options_.vehicle + "' " + what + " within " +
                std::to_string(static_cast<int>(std::lround(options_.timeout_s))) +
                " s (--timeout; domain " + std::to_string(context_.domain_id) + ", service " +
                auv::transfer::listRecordingsService(options_.vehicle) + ")";
  stats_.seconds = secondsSince(start_);
  return PullResult::VEHICLE_LOST;
}

std::string PullSession::waitingForVehicle() const {
  return "waiting for vehicle '" + options_.vehicle + "'";
}

}  // namespace auv::recon::transfer
