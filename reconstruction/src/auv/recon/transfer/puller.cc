#include "auv/recon/transfer/puller.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "auv/recon/transfer/manifest.h"
#include "auv/recon/transfer/pull_session.h"
#include "auv/transfer/bulk_allocator.h"
#include "auv/transfer/names.h"

namespace fs = std::filesystem;

namespace auv::recon::transfer {
namespace {

/// `<survey>/recordings/`, created and locked for this pull: two pulls into one survey would
/// write the same partial files. The lock is released when the object goes.
class RecordingsLock {
 public:
  explicit RecordingsLock(const fs::path& recordings) {
    std::error_code error;
    fs::create_directories(recordings, error);
    if (error) {
      throw std::runtime_error(recordings.string() + ": cannot create: " + error.message());
    }
    const fs::path lock_path = recordings / ".pull.lock";
    fd_ = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) {
      throw std::runtime_error(lock_path.string() + ": cannot open: " + std::strerror(errno));
    }
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      ::close(fd_);
      throw std::runtime_error("another `auv recon pull` is writing into " + recordings.string());
    }
  }
  ~RecordingsLock() { ::close(fd_); }
  RecordingsLock(const RecordingsLock&) = delete;
  RecordingsLock& operator=(const RecordingsLock&) = delete;

 private:
  int fd_ = -1;
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
  const auto start = PullSession::Clock::now();
  stats_ = PullStats{};
  const fs::path recordings = options_.survey / "recordings";
  const RecordingsLock lock(recordings);
  Manifest manifest(recordings / "manifest.json");
  PullContext context{options_,     *impl_->list, *impl_->fetch, impl_->domain_id,
                      on_progress_, on_message_,  stop_,         stats_};
  return PullSession(context, recordings, manifest, start).run();
}

}  // namespace auv::recon::transfer
