#include "auv/recorder/components/recorder_component.h"

#include <cmath>

#include "auv/interfaces/msg_time.h"
#include "auv/interfaces/option_parameters.h"
#include "auv/transfer/bulk_allocator.h"
#include "auv/transfer/names.h"
#include "auv/transfer/sha256.h"

namespace auv::recorder {
namespace {

using transfer::Chunk;
using transfer::ChunkError;

msg::Time secondsToTime(double seconds) {
  return interfaces::toMsgTime(static_cast<int64_t>(std::llround(seconds * 1e9)));
}

}  // namespace

msg::RecordingInfo toRecordingInfo(const Recording& r) {
  msg::RecordingInfo info;
  info.camera_id(r.camera_id);
  info.file_path(r.file_path);
  info.size_bytes(r.size_bytes);
  info.sha256(r.complete ? r.sha256 : "");
  info.start_time(secondsToTime(r.start_time_s));
  info.end_time(secondsToTime(r.end_time_s));
  info.time_synchronised(false);  // the sidecar's camera_time_s: the camera's own clock
  info.frame_count(r.frame_count);
  info.sidecar_file(r.sidecar_file);
  info.sidecar_size_bytes(r.sidecar_size_bytes);
  info.sidecar_sha256(r.complete ? r.sidecar_sha256 : "");
  info.complete(r.complete);
  info.problem(r.problem);
  return info;
}

const config::OptionTable<RecorderComponent::Options>& RecorderComponent::Options::table() {
  using config::Range;
  using O = Options;
  static const config::OptionTable<O> kTable = {
      {"root", &O::root, "recordings root: <root>/<camera>/<name>.mp4 (+ .frames.csv)"},
      {"vehicle_name", &O::vehicle_name,
       "prefix of the recorder's DDS names: <vehicle_name>/recorder/..."},
      {"scan_period", &O::scan_period,
       "seconds between scans of the root (new and closed files are hashed once)", "s",
       Range::closed(0.05, 3600.0)},
      {"max_chunk_bytes", &O::max_chunk_bytes, "cap of one fetch_chunk reply's data", "B",
       Range::closed(4096, static_cast<double>(transfer::kLargestMaxChunkBytes))},
      {"extensions", &O::extensions, "file endings of recordings (with the dot)"},
  };
  return kTable;
}

void RecorderComponent::Options::check() const {
  config::checkOptions(*this, table(), "parameter ");
  if (root.empty()) throw std::invalid_argument("parameter root: empty (the recordings folder)");
  try {
    transfer::checkVehicleName(vehicle_name);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("parameter vehicle_name: ") + e.what());
  }
  CatalogueOptions catalogue{root, extensions};
  try {
    catalogue.check();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("parameter ") + e.what());
  }
}

RecorderComponent::~RecorderComponent() { stopScanner(); }

void RecorderComponent::configure(interfaces::Node& node) {
  node_ = &node;
  auto& p = node.parameters();
  auto& o = options_;
  interfaces::declareOptions(p, "", Options::table(), o, /*read_only=*/true);
  o.check();
  transfer::keepChunkBuffersInHeap();  // every chunk served allocates multi-MiB buffers
  // Chunk digests on the max_chunk_bytes grid, the grid a pull asks for by default: serving
  // a chunk then costs no hashing (reconstruction/bench/README.md).
  catalogue_ =
      std::make_unique<Catalogue>(CatalogueOptions{o.root, o.extensions, o.max_chunk_bytes});
  reader_ = std::make_unique<transfer::ChunkReader>(o.root, o.max_chunk_bytes);
  std::error_code error;
  if (!std::filesystem::is_directory(o.root, error)) {
    AUV_WARN(node.logger(), "recordings root '" << o.root
                                                << "' is not a folder (yet): the catalogue "
                                                   "stays empty until it appears");
  }

  feed_pub_ = node.createPublisher<msg::RecordingInfo>(transfer::recordingsTopic(o.vehicle_name),
                                                       interfaces::latchedStateQos());
  list_service_ = node.createService<msg::RecordingCatalogueRequest, msg::RecordingCatalogueReply>(
      transfer::listRecordingsService(o.vehicle_name),
      [this](const msg::RecordingCatalogueRequest& request, msg::RecordingCatalogueReply& reply) {
        onList(request, reply);
      },
      interfaces::bulkTransferQos());
  fetch_service_ = node.createService<msg::FileChunkRequest, msg::FileChunkReply>(
      transfer::fetchChunkService(o.vehicle_name),
      [this](const msg::FileChunkRequest& request, msg::FileChunkReply& reply) {
        onFetch(request, reply);
      },
      interfaces::bulkTransferQos());
}

void RecorderComponent::activate() {
  std::lock_guard<std::mutex> lock(scanner_mutex_);
  if (scanner_.joinable()) return;
  scanner_stop_ = false;
  scanner_ = std::thread([this] { scanLoop(); });
  AUV_INFO(node_->logger(),
           "serving '" << options_.root << "' as " << options_.vehicle_name << "/recorder/*");
}

void RecorderComponent::deactivate() { stopScanner(); }

void RecorderComponent::cleanup() {
  stopScanner();
  list_service_.reset();
  fetch_service_.reset();
  feed_pub_.reset();
}

void RecorderComponent::stopScanner() {
  {
    std::lock_guard<std::mutex> lock(scanner_mutex_);
    scanner_stop_ = true;
  }
  scanner_wake_.notify_all();
  if (scanner_.joinable()) scanner_.join();
}

void RecorderComponent::scanLoop() {
  std::unique_lock<std::mutex> lock(scanner_mutex_);
  while (!scanner_stop_) {
    lock.unlock();
    scanAndPublish();
    lock.lock();
    scanner_wake_.wait_for(lock, std::chrono::duration<double>(options_.scan_period),
                           [this] { return scanner_stop_ || scan_requested_; });
    scan_requested_ = false;
  }
}

void RecorderComponent::scanNow() { scanAndPublish(); }

void RecorderComponent::requestScan() {
  {
    std::lock_guard<std::mutex> lock(scanner_mutex_);
    scan_requested_ = true;
  }
  scanner_wake_.notify_all();
}

void RecorderComponent::scanAndPublish() {
  std::lock_guard<std::mutex> lock(publish_mutex_);
  const ScanReport report = catalogue_->scan();
  for (const auto& message : report.messages) AUV_WARN(node_->logger(), message);
  if (!report.modified) return;
  // The feed: one sample per recording whose metadata changed (keyed per file).
  for (const Recording& r : catalogue_->list("", true)) {
    msg::RecordingInfo info = toRecordingInfo(r);
    auto it = published_.find(r.file_path);
    if (it != published_.end() && it->second == info) continue;
    feed_pub_->publish(info);
    published_[r.file_path] = std::move(info);
  }
}

void RecorderComponent::onList(const msg::RecordingCatalogueRequest& request,
                               msg::RecordingCatalogueReply& reply) {
  if (!request.camera_id().empty() && !catalogue_->hasCamera(request.camera_id())) {
    throw interfaces::ServiceError(
        msg::REPLY_CODE_NOT_FOUND,
        "camera_id '" + request.camera_id() + "': no such camera folder in the recordings root");
  }
  std::vector<msg::RecordingInfo> recordings;
  for (const Recording& r : catalogue_->list(request.camera_id(), request.include_incomplete())) {
    recordings.push_back(toRecordingInfo(r));
  }
  reply.recordings(std::move(recordings));
  // Asked of the disk now, not of the last scan: a recording closed a moment ago makes the
  // requester wait for its hash (and the scanner is woken for it) instead of being missed.
  const size_t pending = catalogue_->walked() ? catalogue_->pendingNow() : 1;
  if (pending > 0) requestScan();
  reply.pending_files(static_cast<uint32_t>(pending));
  reply.max_chunk_bytes(options_.max_chunk_bytes);
}

void RecorderComponent::onFetch(const msg::FileChunkRequest& request, msg::FileChunkReply& reply) {
  ++chunks_served_;
  reply.file_path(request.file_path());
  reply.offset(request.offset());
  try {
    const auto served = catalogue_->servedFile(request.file_path());
    if (!served) {
      transfer::checkRelativePath(request.file_path());  // a malformed path is named as such
      // Requests already in flight when the first one found the change get the same answer
      // (not "not found", which a puller retries until its timeout).
      if (auto why = catalogue_->changedProblem(request.file_path())) {
        throw interfaces::ServiceError(msg::REPLY_CODE_REJECTED,
                                       "file_path '" + request.file_path() + "': " + *why);
      }
      throw ChunkError(ChunkError::Kind::NOT_FOUND,
                       "file_path '" + request.file_path() +
                           "': not a complete recording or sidecar in the catalogue");
    }
    if (served->relative_path != request.file_path()) {
      throw ChunkError(ChunkError::Kind::NOT_FOUND,
                       "file_path '" + request.file_path() + "': not a complete file");
    }
    Chunk chunk =
        reader_->read(request.file_path(), request.offset(), request.length(), served->stamp);
    // Kept since cataloguing for chunks on the catalogue's grid (the bytes were read in the
    // state `served->stamp`, checked by read()); hashed here for any other range.
    const std::optional<std::string> kept = catalogue_->chunkDigest(
        request.file_path(), served->stamp, request.offset(), chunk.data.size());
    reply.data_sha256(kept ? *kept : Sha256::of(chunk.data.data(), chunk.data.size()));
    reply.total_size(chunk.total_size);
    reply.eof(request.offset() + chunk.data.size() == chunk.total_size);
    if (chunk_observer_) chunk_observer_(request.file_path(), request.offset(), chunk.data.size());
    reply.data(std::move(chunk.data));
  } catch (const ChunkError& e) {
    switch (e.kind()) {
      case ChunkError::Kind::INVALID_PATH:
      case ChunkError::Kind::BAD_RANGE:
        throw interfaces::ServiceError(msg::REPLY_CODE_INVALID_ARGUMENT, e.what());
      case ChunkError::Kind::NOT_FOUND:
        throw interfaces::ServiceError(msg::REPLY_CODE_NOT_FOUND, e.what());
      case ChunkError::Kind::CHANGED: {
        catalogue_->reportChanged(request.file_path(), e.what());
        AUV_WARN(node_->logger(), e.what() << ": no longer served as complete");
        requestScan();
        throw interfaces::ServiceError(msg::REPLY_CODE_REJECTED, e.what());
      }
      case ChunkError::Kind::IO:
        throw interfaces::ServiceError(msg::REPLY_CODE_IO_ERROR, e.what());
    }
    throw;
  }
}

}  // namespace auv::recorder

AUV_REGISTER_COMPONENT(auv::recorder::RecorderComponent, "recorder",
                       "serves the vehicle's recordings (catalogue, file chunks) to the shore")
