// PullSession's fetching: the window of chunk requests in flight and what is done with each
// reply (pull_session.h; the rest of the session is in pull_session.cc).
#include "auv/recon/transfer/pull_session.h"

#include <algorithm>
#include <thread>

#include "auv/transfer/sha256.h"

using namespace std::chrono_literals;

namespace auv::recon::transfer {

// --- Fetching, several chunks in flight.

std::optional<PullResult> PullSession::fetchAll(uint32_t max_chunk) {
  window_ = Window{};
  window_.rate_since = Clock::now();
  window_.service_was_ready = context_.fetch.serviceReady();
  while (!round_.queue.empty() || !window_.flight.empty()) {
    if (context_.stop) return interrupted();
    if (Clock::now() - last_alive_ > timeout_) return lost("stopped answering and did not return");
    const bool ready = context_.fetch.serviceReady();
    noticeVehicleChange(ready);
    progress_.waiting = ready ? "" : waitingForVehicle();
    if (ready) fillWindow();
    if (window_.flight.empty()) {
      std::this_thread::sleep_for(20ms);
      report(false);
      continue;
    }
    window_.flight.front().reply.wait_for(20ms);
    collectReplies(max_chunk);
    report(false);
  }
  return std::nullopt;
}

void PullSession::noticeVehicleChange(bool ready) {
  if (ready == window_.service_was_ready) return;
  if (!ready) {
    message("vehicle '" + options_.vehicle + "' went away; waiting up to " +
            std::to_string(static_cast<int>(options_.timeout_s)) + " s for it");
  } else {
    ++stats_.vehicle_restarts;
    message("vehicle '" + options_.vehicle + "' is back; resuming");
  }
  window_.fetch_answered = false;
  window_.service_was_ready = ready;
}

size_t PullSession::windowSize() const {
  return window_.fetch_answered ? static_cast<size_t>(options_.in_flight) : 1;
}

void PullSession::fillWindow() {
  const auto now = Clock::now();
  while (window_.flight.size() < windowSize() && !round_.queue.empty()) {
    auto it = std::find_if(round_.queue.begin(), round_.queue.end(),
                           [&](const Work& w) { return w.not_before <= now; });
    if (it == round_.queue.end()) break;
    Work work = *it;
    round_.queue.erase(it);
    if (work.file->failed || work.file->task->failed) continue;  // its recording failed
    msg::FileChunkRequest request;
    request.file_path(work.file->partial->remote().path);
    request.offset(work.offset);
    request.length(work.length);
    if (!window_.fetch_answered && !probeReplyPath(request)) {
      round_.queue.push_front(work);  // --timeout (last_alive_) decides when to give up
      break;
    }
    stats_.bytes_requested += work.length;
    ++work.file->in_flight;
    window_.flight.push_back(InFlight{work, context_.fetch.callAsync(request), Clock::now()});
  }
}

/// The zero-length request that precedes the pipelined chunks (Window::fetch_answered).
bool PullSession::probeReplyPath(const msg::FileChunkRequest& request) {
  msg::FileChunkRequest probe = request;
  probe.length(0);
  msg::FileChunkReply answer;  // its status does not matter: an answer came back
  if (context_.fetch.call(probe, &answer, 2000ms, 50ms) != interfaces::CallStatus::OK) {
    return false;
  }
  window_.fetch_answered = true;
  return true;
}

void PullSession::collectReplies(uint32_t max_chunk) {
  // A request unanswered for this long is asked again: generous against the measured rate,
  // since the whole window drains ahead of the last request.
  const double window_bytes =
      static_cast<double>(options_.in_flight) * static_cast<double>(max_chunk);
  const double request_timeout_s = 5.0 + 4.0 * window_bytes / std::max(window_.rate, 1e6);
  auto& flight = window_.flight;
  for (auto it = flight.begin(); it != flight.end();) {
    if (it->reply.wait_for(0s) != std::future_status::ready) {
      if (secondsSince(it->sent) > request_timeout_s) {
        ++stats_.requests_timed_out;
        --it->work.file->in_flight;
        it->work.not_before = Clock::now();
        round_.queue.push_front(it->work);
        it = flight.erase(it);
      } else {
        ++it;
      }
      continue;
    }
    const msg::FileChunkReply reply = it->reply.get();
    const Work work = it->work;
    it = flight.erase(it);
    handleReply(work, reply);
  }
}

void PullSession::handleReply(Work work, const msg::FileChunkReply& reply) {
  FileState& file = *work.file;
  --file.in_flight;
  last_alive_ = Clock::now();
  if (file.failed || file.task->failed) return;
  const auto code = reply.status().code();
  if (code == msg::REPLY_CODE_REJECTED) {
    failFile(file, "changed on the vehicle during the pull: " + reply.status().error_text() +
                       " (not pulled; partial file kept)");
    return;
  }
  if (code != msg::REPLY_CODE_OK) {
    retryLater(file, work, reply);
    return;
  }
  file.not_found_since.reset();
  const auto& data = reply.data();
  countReceived(data.size());
  if (!replyMatches(file, work, reply)) return;
  const uint64_t chunk_start = file.partial->chunkOffset(work.chunk);
  const uint32_t chunk_length = file.partial->chunkLength(work.chunk);
  const bool whole_chunk = work.offset == chunk_start && data.size() == chunk_length;
  // A whole chunk is written with the digest the vehicle sent and checked by the whole-file
  // SHA-256 in finish(), which names the chunks to fetch again if it fails: one hashing pass
  // on shore instead of two. Pieces of a chunk are checked now.
  const bool corrupted =
      !auv::transfer::isSha256Hex(reply.data_sha256()) ||
      (!whole_chunk && auv::transfer::Sha256::of(data.data(), data.size()) != reply.data_sha256());
  if (corrupted) {
    handleCorrupted(file, work);
    return;
  }
  progress_.current_file = file.partial->remote().path;
  bool chunk_complete = true;
  if (whole_chunk) {
    file.partial->writeChunk(work.chunk, data.data(), data.size(), reply.data_sha256());
  } else {
    chunk_complete = storePiece(file, work, data);
  }
  progress_.bytes_done += data.size();
  if (!chunk_complete) return;
  finishIfComplete(file);
  report(false);
}

/// NOT_FOUND while a restarted recorder re-hashes its files, BUSY, I/O errors: ask again a
/// little later, for up to --timeout.
void PullSession::retryLater(FileState& file, Work work, const msg::FileChunkReply& reply) {
  if (!file.not_found_since) file.not_found_since = Clock::now();
  if (Clock::now() - *file.not_found_since > timeout_) {
    failFile(file, "the vehicle stopped serving it: " + reply.status().error_text());
    return;
  }
  work.not_before = Clock::now() + 500ms;
  round_.queue.push_back(work);
}

void PullSession::countReceived(size_t bytes) {
  stats_.bytes_received += bytes;
  window_.rate_bytes += bytes;
  if (secondsSince(window_.rate_since) > 0.5) {
    const double measured = window_.rate_bytes / secondsSince(window_.rate_since);
    window_.rate = window_.rate == 0 ? measured : 0.5 * window_.rate + 0.5 * measured;
    window_.rate_since = Clock::now();
    window_.rate_bytes = 0;
  }
}

/// False (and the file failed) if the reply is not for the file in its catalogued state or
/// not for the range asked.
bool PullSession::replyMatches(FileState& file, const Work& work,
                               const msg::FileChunkReply& reply) {
  const RemoteFile& remote = file.partial->remote();
  const auto& data = reply.data();
  if (reply.total_size() != remote.size) {
    failFile(file, "the vehicle now reports " + std::to_string(reply.total_size()) +
                       " bytes, catalogued " + std::to_string(remote.size) +
                       " (changed on the vehicle; not pulled)");
    return false;
  }
  if (reply.offset() != work.offset || data.size() > work.length ||
      (data.empty() && work.length > 0)) {
    failFile(file, "the vehicle answered offset " + std::to_string(reply.offset()) + " with " +
                       std::to_string(data.size()) + " bytes for a request of " +
                       std::to_string(work.length) + " bytes at " + std::to_string(work.offset));
    return false;
  }
  return true;
}

void PullSession::handleCorrupted(FileState& file, const Work& work) {
  ++stats_.chunks_corrupted;
  if (++file.corrupted > kMaxCorruptedChunksPerFile) {
    failFile(file, std::to_string(file.corrupted) +
                       " chunks arrived corrupted (SHA-256 mismatch); giving up");
    return;
  }
  message(file.partial->remote().path + ": chunk at offset " + std::to_string(work.offset) +
          " arrived corrupted (SHA-256 mismatch); fetching it again");
  round_.queue.push_front(work);
}

/// A piece of a chunk (the recorder caps chunks lower than ours): kept until the chunk is
/// whole, then written with its digest. False while the rest is still to come (asked for).
bool PullSession::storePiece(FileState& file, const Work& work, const std::vector<uint8_t>& data) {
  const uint64_t chunk_start = file.partial->chunkOffset(work.chunk);
  const uint32_t chunk_length = file.partial->chunkLength(work.chunk);
  std::vector<uint8_t>& buffer = file.buffers[work.chunk];
  buffer.resize(chunk_length);
  std::copy(data.begin(), data.end(), buffer.begin() + (work.offset - chunk_start));
  const uint64_t received_to = work.offset + data.size();
  if (received_to < chunk_start + chunk_length) {
    round_.queue.push_front(Work{&file, work.chunk, received_to,
                                 static_cast<uint32_t>(chunk_start + chunk_length - received_to)});
    return false;
  }
  file.partial->writeChunk(work.chunk, buffer.data(), buffer.size(),
                           auv::transfer::Sha256::of(buffer.data(), buffer.size()));
  file.buffers.erase(work.chunk);
  return true;
}

}  // namespace auv::recon::transfer
