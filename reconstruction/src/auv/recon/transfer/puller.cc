#include "auv/recon/transfer/puller.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <deque>
#include <future>
#include <map>
#include <optional>
#include <set>
#include <thread>

#include "auv/interfaces/msg_time.h"
#include "auv/recon/transfer/manifest.h"
#include "auv/recon/transfer/partial_file.h"
#include "auv/transfer/bulk_allocator.h"
#include "auv/transfer/chunk_reader.h"
#include "auv/transfer/names.h"
#include "auv/transfer/sha256.h"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

namespace auv::recon::transfer {
namespace {

using ListClient = interfaces::Client<msg::RecordingCatalogueRequest, msg::RecordingCatalogueReply>;
using FetchClient = interfaces::Client<msg::FileChunkRequest, msg::FileChunkReply>;

double secondsSince(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

double toSeconds(const msg::Time& t) { return interfaces::toNanoseconds(t) * 1e-9; }

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

/// A link that corrupts this many chunks of one file is not worth retrying.
constexpr size_t kMaxCorruptedChunksPerFile = 16;

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

}  // namespace

struct Puller::Impl {
  std::shared_ptr<ListClient> list;
  std::shared_ptr<FetchClient> fetch;
  int domain_id = 0;
};

void PullOptions::check() const {
  try {
    auv::transfer::checkVehicleName(vehicle);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--vehicle: ") + e.what());
  }
  if (survey.empty()) throw std::invalid_argument("--into: missing survey folder");
  if (!(timeout_s > 0) || !std::isfinite(timeout_s)) {
    throw std::invalid_argument("--timeout: must be a positive number of seconds");
  }
  if (in_flight < 1 || in_flight > 256) {
    throw std::invalid_argument("--in-flight: " + std::to_string(in_flight) +
                                " is outside [1, 256] (the bulk_transfer profile keeps 256)");
  }
  if (chunk_bytes < 4096 || chunk_bytes > auv::transfer::kLargestMaxChunkBytes) {
    throw std::invalid_argument("--chunk-bytes: " + std::to_string(chunk_bytes) +
                                " is outside [4096, " +
                                std::to_string(auv::transfer::kLargestMaxChunkBytes) + "]");
  }
  for (const auto& camera : cameras) {
    if (camera.empty() || camera.find('/') != std::string::npos || camera == "." ||
        camera == "..") {
      throw std::invalid_argument("--camera: '" + camera + "' is not a camera id");
    }
  }
}

Puller::Puller(interfaces::Node& node, PullOptions options)
    : impl_(std::make_unique<Impl>()), options_(std::move(options)) {
  options_.check();
  auv::transfer::keepChunkBuffersInHeap();  // every chunk received allocates multi-MiB buffers
  impl_->list = node.createClient<msg::RecordingCatalogueRequest, msg::RecordingCatalogueReply>(
      auv::transfer::listRecordingsService(options_.vehicle), interfaces::bulkTransferQos());
  impl_->fetch = node.createClient<msg::FileChunkRequest, msg::FileChunkReply>(
      auv::transfer::fetchChunkService(options_.vehicle), interfaces::bulkTransferQos());
  impl_->domain_id = node.domainId();
}

Puller::~Puller() = default;

bool Puller::vehicleReady() const {
  return impl_->list->serviceReady() && impl_->fetch->serviceReady();
}

PullResult Puller::run() {
  const auto start = Clock::now();
  stats_ = PullStats{};
  auto message = [&](const std::string& text) {
    if (on_message_) on_message_(text);
  };
  const fs::path recordings = options_.survey / "recordings";
  std::error_code error;
  fs::create_directories(recordings, error);
  if (error) {
    throw std::runtime_error(recordings.string() + ": cannot create: " + error.message());
  }
  // One pull per survey at a time: two would write the same partial files.
  const fs::path lock_path = recordings / ".pull.lock";
  const int lock_fd = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (lock_fd < 0) {
    throw std::runtime_error(lock_path.string() + ": cannot open: " + std::strerror(errno));
  }
  struct LockCloser {
    int fd;
    ~LockCloser() { ::close(fd); }
  } lock_closer{lock_fd};
  if (::flock(lock_fd, LOCK_EX | LOCK_NB) != 0) {
    throw std::runtime_error("another `auv recon pull` is writing into " + recordings.string());
  }
  Manifest manifest(recordings / "manifest.json");

  PullProgress progress;
  auto last_progress_call = Clock::now() - 1s;
  auto report = [&](bool force) {
    if (!on_progress_) return;
    if (!force && secondsSince(last_progress_call) < options_.progress_period_s) return;
    last_progress_call = Clock::now();
    on_progress_(progress);
  };

  auto last_alive = Clock::now();
  const auto timeout = std::chrono::duration<double>(options_.timeout_s);
  auto lost = [&](const std::string& what) {
    stats_.lost = "vehicle '" + options_.vehicle + "' " + what + " within " +
                  std::to_string(static_cast<int>(std::lround(options_.timeout_s))) +
                  " s (--timeout; domain " + std::to_string(impl_->domain_id) + ", service " +
                  auv::transfer::listRecordingsService(options_.vehicle) + ")";
    stats_.seconds = secondsSince(start);
    return PullResult::VEHICLE_LOST;
  };

  std::set<std::string> failed_files;  // "<path> <sha256>": not tried again in later rounds
  std::set<std::string> reported;      // recordings with a problem line already
  bool was_ready = false;
  for (;;) {  // rounds: list, pull what is new; again while the vehicle is still hashing
    // --- wait for the vehicle, list.
    std::vector<msg::RecordingInfo> listed;
    uint32_t pending = 0;
    uint32_t server_max_chunk = options_.chunk_bytes;
    const std::vector<std::string> cameras =
        options_.cameras.empty() ? std::vector<std::string>{""} : options_.cameras;
    for (const auto& camera : cameras) {
      msg::RecordingCatalogueRequest request;
      request.camera_id(camera);
      request.include_incomplete(true);
      msg::RecordingCatalogueReply reply;
      for (;;) {
        if (stop_) {
          stats_.seconds = secondsSince(start);
          return PullResult::INTERRUPTED;
        }
        const auto remaining = timeout - (Clock::now() - last_alive);
        if (remaining <= 0s) return lost(was_ready ? "did not answer" : "was not found");
        progress.waiting =
            impl_->list->serviceReady() ? "" : "waiting for vehicle '" + options_.vehicle + "'";
        report(true);
        // Short calls, so stop() and the deadline are honoured promptly.
        const auto slice = std::min<std::chrono::milliseconds>(
            2000ms, std::chrono::duration_cast<std::chrono::milliseconds>(remaining) + 1ms);
        if (impl_->list->call(request, &reply, slice) == interfaces::CallStatus::OK) break;
      }
      last_alive = Clock::now();
      if (!was_ready) {
        message("vehicle '" + options_.vehicle + "' found");
        was_ready = true;
      }
      progress.waiting.clear();
      if (reply.status().code() == msg::REPLY_CODE_NOT_FOUND && !camera.empty()) {
        if (reported.insert("camera " + camera).second) {
          stats_.problems.push_back("camera '" + camera + "': " + reply.status().error_text());
        }
        continue;
      }
      if (reply.status().code() != msg::REPLY_CODE_OK) {
        throw std::runtime_error("vehicle '" + options_.vehicle +
                                 "' refused the catalogue request: " + reply.status().error_text());
      }
      pending += reply.pending_files();
      if (reply.max_chunk_bytes() > 0) {
        server_max_chunk = std::min(server_max_chunk, reply.max_chunk_bytes());
      }
      for (const auto& info : reply.recordings()) listed.push_back(info);
    }

    // --- decide what to fetch.
    std::deque<Task> tasks;
    std::deque<FileState> files;
    std::deque<Work> queue;
    size_t complete_listed = 0, being_written = 0;
    for (const auto& info : listed) {
      if (!info.complete()) {
        const ManifestEntry* have = manifest.find(info.file_path());
        if (!info.problem().empty() && have == nullptr) {
          if (reported.insert(info.file_path()).second) {
            stats_.problems.push_back(info.file_path() + ": not pulled: " + info.problem());
            message(stats_.problems.back());
          }
        } else if (!info.problem().empty()) {
          message(info.file_path() + ": the vehicle's copy " + info.problem() +
                  "; the copy verified on shore is kept");
        } else {
          ++being_written;
        }
        continue;
      }
      ++complete_listed;
      // Paths come from the network: they must stay inside recordings/.
      try {
        auv::transfer::checkRelativePath(info.file_path());
        if (!info.sidecar_file().empty()) auv::transfer::checkRelativePath(info.sidecar_file());
        if (!auv::transfer::isSha256Hex(info.sha256()) ||
            (!info.sidecar_file().empty() && !auv::transfer::isSha256Hex(info.sidecar_sha256()))) {
          throw std::invalid_argument("catalogue entry without a valid sha256");
        }
      } catch (const std::exception& e) {
        if (reported.insert(info.file_path()).second) {
          stats_.problems.push_back(info.file_path() + ": not pulled: " + e.what());
        }
        continue;
      }
      if (failed_files.count(info.file_path() + " " + info.sha256())) continue;
      const ManifestEntry* have = manifest.find(info.file_path());
      if (have != nullptr && have->sha256 == info.sha256() &&
          have->sidecar_sha256 == info.sidecar_sha256() && fs::exists(recordings / have->file)) {
        continue;  // verified before
      }
      tasks.push_back(Task{info});
      Task& task = tasks.back();
      std::vector<RemoteFile> remote = {{info.file_path(), info.size_bytes(), info.sha256()}};
      if (!info.sidecar_file().empty()) {
        remote.push_back({info.sidecar_file(), info.sidecar_size_bytes(), info.sidecar_sha256()});
      }
      for (const auto& r : remote) {
        const fs::path final_path = recordings / r.path;
        if (fs::exists(final_path)) {
          // On disk under its final name but not in the manifest (e.g. interrupted just
          // after the rename): verified by hashing, never overwritten.
          std::string local;
          try {
            local = auv::transfer::sha256OfFile(final_path);
          } catch (const std::exception& e) {
            local = e.what();
          }
          if (local != r.sha256) {
            task.failed = true;
            failed_files.insert(info.file_path() + " " + info.sha256());
            stats_.problems.push_back(r.path + ": " + final_path.string() +
                                      " exists and differs from the vehicle's file (sha256 " +
                                      r.sha256.substr(0, 12) +
                                      "...); move it away to pull it again");
            message(stats_.problems.back());
          }
          continue;
        }
        files.emplace_back();
        FileState& file = files.back();
        file.task = &task;
        file.partial = std::make_unique<PartialFile>(final_path, r, server_max_chunk);
        if (!file.partial->startNote().empty()) {
          message(r.path + ": " + file.partial->startNote());
        }
        if (file.partial->reusedChunks() > 0 || file.partial->droppedChunks() > 0) {
          message(r.path + ": resumed, " + std::to_string(file.partial->reusedChunks()) +
                  " chunks on disk re-verified" +
                  (file.partial->droppedChunks() > 0
                       ? ", " + std::to_string(file.partial->droppedChunks()) +
                             " failed their digest and are fetched again"
                       : ""));
        }
        stats_.chunks_reused += file.partial->reusedChunks();
        stats_.chunks_dropped += file.partial->droppedChunks();
        const uint64_t missing = file.partial->missingBytes();
        stats_.bytes_missing += missing;
        progress.bytes_total += missing;
        ++task.files_left;
        for (size_t i = 0; i < file.partial->chunkCount(); ++i) {
          if (!file.partial->has(i)) {
            queue.push_back(
                Work{&file, i, file.partial->chunkOffset(i), file.partial->chunkLength(i)});
          }
        }
      }
    }
    stats_.recordings_on_vehicle = complete_listed;
    stats_.recordings_being_written = being_written;

    auto recordIfDone = [&](Task& task) {
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
      manifest.record(entry);
      ++stats_.recordings_pulled;
    };
    auto failTask = [&](FileState& file, const std::string& why) {
      if (file.failed) return;
      file.failed = true;
      failed_files.insert(file.partial->remote().path + " " + file.partial->remote().sha256);
      if (!file.task->failed) {
        file.task->failed = true;
        reported.insert(file.task->info.file_path());
        stats_.problems.push_back(file.partial->remote().path + ": " + why);
        message(stats_.problems.back());
      }
    };
    auto finishIfComplete = [&](FileState& file) {
      if (file.failed || file.task->failed || file.done || !file.partial->allChunks() ||
          file.in_flight > 0) {
        return;
      }
      try {
        const std::vector<size_t> bad = file.partial->finish();
        if (!bad.empty()) {
          // Found by the whole-file check: fetch those chunks again, alone.
          for (size_t index : bad) {
            const uint64_t offset = file.partial->chunkOffset(index);
            ++stats_.chunks_corrupted;
            ++file.corrupted;
            message(file.partial->remote().path + ": chunk at offset " + std::to_string(offset) +
                    " arrived corrupted (SHA-256 mismatch); fetching it again");
            queue.push_front(Work{&file, index, offset, file.partial->chunkLength(index)});
          }
          if (file.corrupted > kMaxCorruptedChunksPerFile) {
            failTask(file, std::to_string(file.corrupted) +
                               " chunks arrived corrupted (SHA-256 mismatch); giving up");
          }
          return;
        }
        file.done = true;
        ++stats_.files_pulled;
        --file.task->files_left;
        recordIfDone(*file.task);
      } catch (const VerifyError& e) {
        failTask(file, e.what());
      }
    };
    // Files with nothing to fetch (all chunks re-verified on disk) finish now.
    for (auto& file : files) finishIfComplete(file);
    for (auto& task : tasks) {
      if (task.files_left == 0 && !task.failed) recordIfDone(task);
    }

    // --- fetch, several chunks in flight.
    std::deque<InFlight> flight;
    double rate = 0;  // bytes/s, smoothed: sizes the request timeout
    auto rate_since = Clock::now();
    uint64_t rate_bytes = 0;
    bool service_was_ready = impl_->fetch->serviceReady();
    // Until the recorder has answered one fetch_chunk request, its reply writer may not have
    // discovered our reader yet (discovery is asymmetric) and would drop what it writes: a
    // zero-length request goes out first with call(), repeated every 50 ms (cheap, where
    // repeating a whole chunk would send it twice on a slow link; the default 500 ms cost
    // half a second of many pulls); the chunks are pipelined with callAsync() once it is
    // answered. Again after the vehicle comes back (new writers).
    bool fetch_answered = false;
    while (!queue.empty() || !flight.empty()) {
      if (stop_) {
        stats_.seconds = secondsSince(start);
        return PullResult::INTERRUPTED;
      }
      if (Clock::now() - last_alive > timeout) return lost("stopped answering and did not return");
      const bool ready = impl_->fetch->serviceReady();
      if (ready != service_was_ready) {
        if (!ready) {
          message("vehicle '" + options_.vehicle + "' went away; waiting up to " +
                  std::to_string(static_cast<int>(options_.timeout_s)) + " s for it");
        } else {
          ++stats_.vehicle_restarts;
          message("vehicle '" + options_.vehicle + "' is back; resuming");
        }
        fetch_answered = false;
        service_was_ready = ready;
      }
      progress.waiting = ready ? "" : "waiting for vehicle '" + options_.vehicle + "'";
      // Fill the window.
      const auto now = Clock::now();
      const auto window = [&] {
        return fetch_answered ? static_cast<size_t>(options_.in_flight) : 1;
      };
      while (ready && flight.size() < window() && !queue.empty()) {
        auto it = std::find_if(queue.begin(), queue.end(),
                               [&](const Work& w) { return w.not_before <= now; });
        if (it == queue.end()) break;
        Work work = *it;
        queue.erase(it);
        if (work.file->failed || work.file->task->failed) continue;  // its recording failed
        msg::FileChunkRequest request;
        request.file_path(work.file->partial->remote().path);
        request.offset(work.offset);
        request.length(work.length);
        if (!fetch_answered) {
          msg::FileChunkRequest probe = request;
          probe.length(0);
          msg::FileChunkReply answer;  // its status does not matter: an answer came back
          if (impl_->fetch->call(probe, &answer, 2000ms, 50ms) != interfaces::CallStatus::OK) {
            queue.push_front(work);  // --timeout (last_alive) decides when to give up
            break;
          }
          fetch_answered = true;
        }
        stats_.bytes_requested += work.length;
        ++work.file->in_flight;
        flight.push_back(InFlight{work, impl_->fetch->callAsync(request), Clock::now()});
      }
      if (flight.empty()) {
        std::this_thread::sleep_for(20ms);
        report(false);
        continue;
      }
      flight.front().reply.wait_for(20ms);
      // A request unanswered for this long is asked again: generous against the measured rate,
      // since the whole window drains ahead of the last request.
      const double window_bytes =
          static_cast<double>(options_.in_flight) * static_cast<double>(server_max_chunk);
      const double request_timeout_s = 5.0 + 4.0 * window_bytes / std::max(rate, 1e6);
      for (auto it = flight.begin(); it != flight.end();) {
        const bool arrived = it->reply.wait_for(0s) == std::future_status::ready;
        if (!arrived) {
          if (secondsSince(it->sent) > request_timeout_s) {
            ++stats_.requests_timed_out;
            --it->work.file->in_flight;
            it->work.not_before = Clock::now();
            queue.push_front(it->work);
            it = flight.erase(it);
          } else {
            ++it;
          }
          continue;
        }
        msg::FileChunkReply reply = it->reply.get();
        Work work = it->work;
        it = flight.erase(it);
        FileState& file = *work.file;
        --file.in_flight;
        last_alive = Clock::now();
        if (file.failed || file.task->failed) continue;
        const RemoteFile& remote = file.partial->remote();
        const auto code = reply.status().code();
        if (code == msg::REPLY_CODE_REJECTED) {
          failTask(file, "changed on the vehicle during the pull: " + reply.status().error_text() +
                             " (not pulled; partial file kept)");
          continue;
        }
        if (code != msg::REPLY_CODE_OK) {
          // NOT_FOUND while a restarted recorder re-hashes its files, BUSY, I/O errors:
          // ask again a little later, for up to --timeout.
          if (!file.not_found_since) file.not_found_since = Clock::now();
          if (Clock::now() - *file.not_found_since > timeout) {
            failTask(file, "the vehicle stopped serving it: " + reply.status().error_text());
          } else {
            work.not_before = Clock::now() + 500ms;
            queue.push_back(work);
          }
          continue;
        }
        file.not_found_since.reset();
        const auto& data = reply.data();
        stats_.bytes_received += data.size();
        rate_bytes += data.size();
        if (secondsSince(rate_since) > 0.5) {
          const double measured = rate_bytes / secondsSince(rate_since);
          rate = rate == 0 ? measured : 0.5 * rate + 0.5 * measured;
          rate_since = Clock::now();
          rate_bytes = 0;
        }
        if (reply.total_size() != remote.size) {
          failTask(file, "the vehicle now reports " + std::to_string(reply.total_size()) +
                             " bytes, catalogued " + std::to_string(remote.size) +
                             " (changed on the vehicle; not pulled)");
          continue;
        }
        if (reply.offset() != work.offset || data.size() > work.length ||
            (data.empty() && work.length > 0)) {
          failTask(file, "the vehicle answered offset " + std::to_string(reply.offset()) +
                             " with " + std::to_string(data.size()) + " bytes for a request of " +
                             std::to_string(work.length) + " bytes at " +
                             std::to_string(work.offset));
          continue;
        }
        const uint64_t chunk_start = file.partial->chunkOffset(work.chunk);
        const uint32_t chunk_length = file.partial->chunkLength(work.chunk);
        const bool whole_chunk = work.offset == chunk_start && data.size() == chunk_length;
        // A whole chunk is written with the digest the vehicle sent and checked by the
        // whole-file SHA-256 in finish(), which names the chunks to fetch again if it fails:
        // one hashing pass on shore instead of two. Pieces of a chunk are checked now.
        const bool corrupted =
            !auv::transfer::isSha256Hex(reply.data_sha256()) ||
            (!whole_chunk &&
             auv::transfer::Sha256::of(data.data(), data.size()) != reply.data_sha256());
        if (corrupted) {
          ++stats_.chunks_corrupted;
          if (++file.corrupted > kMaxCorruptedChunksPerFile) {
            failTask(file, std::to_string(file.corrupted) +
                               " chunks arrived corrupted (SHA-256 mismatch); giving up");
            continue;
          }
          message(remote.path + ": chunk at offset " + std::to_string(work.offset) +
                  " arrived corrupted (SHA-256 mismatch); fetching it again");
          queue.push_front(work);
          continue;
        }
        progress.current_file = remote.path;
        if (whole_chunk) {
          file.partial->writeChunk(work.chunk, data.data(), data.size(), reply.data_sha256());
        } else {
          std::vector<uint8_t>& buffer = file.buffers[work.chunk];
          buffer.resize(chunk_length);
          std::copy(data.begin(), data.end(), buffer.begin() + (work.offset - chunk_start));
          const uint64_t received_to = work.offset + data.size();
          if (received_to < chunk_start + chunk_length) {
            // A short reply (the recorder caps chunks lower than ours): ask for the rest.
            queue.push_front(Work{&file, work.chunk, received_to,
                                  static_cast<uint32_t>(chunk_start + chunk_length - received_to)});
            progress.bytes_done += data.size();
            continue;
          }
          file.partial->writeChunk(work.chunk, buffer.data(), buffer.size(),
                                   auv::transfer::Sha256::of(buffer.data(), buffer.size()));
          file.buffers.erase(work.chunk);
          progress.bytes_done += data.size();
          finishIfComplete(file);
          report(false);
          continue;
        }
        progress.bytes_done += data.size();
        finishIfComplete(file);
        report(false);
      }
      report(false);
    }
    for (auto& file : files) finishIfComplete(file);
    report(true);

    stats_.recordings_present = 0;
    stats_.recordings_failed = 0;
    for (const auto& info : listed) {
      if (!info.complete()) continue;
      const ManifestEntry* have = manifest.find(info.file_path());
      if (have != nullptr && have->sha256 == info.sha256()) {
        ++stats_.recordings_present;
      } else {
        ++stats_.recordings_failed;
      }
    }
    stats_.recordings_present -= std::min(stats_.recordings_present, stats_.recordings_pulled);
    // Another round if the vehicle is still hashing, or if this one fetched something (new
    // recordings may have closed meanwhile); done when a round finds nothing new.
    if (pending > 0) {
      progress.waiting = "vehicle is cataloguing " + std::to_string(pending) + " files";
      report(true);
      std::this_thread::sleep_for(500ms);
      continue;
    }
    if (tasks.empty()) break;
  }
  stats_.recordings_failed = stats_.problems.size();
  stats_.seconds = secondsSince(start);
  return stats_.problems.empty() ? PullResult::COMPLETE : PullResult::FAILED_FILES;
}

}  // namespace auv::recon::transfer
