#include "auv/recon/transfer/partial_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include "auv/transfer/sha256.h"

namespace fs = std::filesystem;

namespace auv::recon::transfer {
namespace {

constexpr char kMagic[] = "auv-pull-progress 1";

[[noreturn]] void ioError(const fs::path& path, const std::string& what) {
  throw std::runtime_error(path.string() + ": " + what + ": " + std::strerror(errno));
}

void writeAll(int fd, const void* data, size_t size, uint64_t offset, const fs::path& path) {
  const auto* bytes = static_cast<const uint8_t*>(data);
  size_t done = 0;
  while (done < size) {
    const ssize_t n = ::pwrite(fd, bytes + done, size - done, static_cast<off_t>(offset + done));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) ioError(path, "write failed");
    done += static_cast<size_t>(n);
  }
}

void syncFolder(const fs::path& folder) {
  const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

}  // namespace

fs::path PartialFile::partPath(const fs::path& final_path) { return final_path.string() + ".part"; }
fs::path PartialFile::progressPath(const fs::path& final_path) {
  return final_path.string() + ".part.progress";
}

PartialFile::PartialFile(fs::path final_path, RemoteFile remote, uint32_t chunk_bytes)
    : final_path_(std::move(final_path)), remote_(std::move(remote)), chunk_bytes_(chunk_bytes) {
  if (chunk_bytes_ == 0) throw std::invalid_argument("chunk size must be > 0");
  fs::create_directories(final_path_.parent_path());
  if (!loadRecord()) startFresh();
}

PartialFile::~PartialFile() {
  if (fd_ >= 0) ::close(fd_);
  if (record_fd_ >= 0) ::close(record_fd_);
}

uint32_t PartialFile::chunkLength(size_t index) const {
  const uint64_t offset = chunkOffset(index);
  return static_cast<uint32_t>(std::min<uint64_t>(chunk_bytes_, remote_.size - offset));
}

uint64_t PartialFile::missingBytes() const {
  uint64_t missing = 0;
  for (size_t i = 0; i < have_.size(); ++i) {
    if (!have_[i]) missing += chunkLength(i);
  }
  return missing;
}

bool PartialFile::loadRecord() {
  std::ifstream in(progressPath(final_path_));
  if (!in) return false;
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // Only whole lines count: the last one may have been cut by the interruption.
  const size_t last_newline = text.rfind('\n');
  text.resize(last_newline == std::string::npos ? 0 : last_newline + 1);
  std::istringstream lines(text);
  std::string line, file, sha;
  uint64_t size = 0;
  uint32_t chunk_bytes = 0;
  std::getline(lines, line);
  if (line != kMagic) {
    start_note_ = "progress record unreadable (no '" + std::string(kMagic) + "' header); restarted";
    return false;
  }
  std::map<size_t, std::string> chunks;
  while (std::getline(lines, line)) {
    std::istringstream fields(line);
    std::string key;
    fields >> key;
    if (key == "file") {
      std::getline(fields >> std::ws, file);
    } else if (key == "size") {
      fields >> size;
    } else if (key == "sha256") {
      fields >> sha;
    } else if (key == "chunk_bytes") {
      fields >> chunk_bytes;
    } else if (key == "chunk") {
      size_t index = 0;
      std::string digest;
      if ((fields >> index >> digest) && auv::transfer::isSha256Hex(digest)) chunks[index] = digest;
    }
  }
  if (file != remote_.path || size != remote_.size || sha != remote_.sha256 || chunk_bytes == 0) {
    start_note_ = "partial file was for another version of the file (vehicle's sha256 " +
                  remote_.sha256.substr(0, 12) + "..., record's " + sha.substr(0, 12) +
                  "...); restarted";
    return false;
  }
  fd_ = ::open(partPath(final_path_).c_str(), O_RDWR | O_CLOEXEC);
  if (fd_ < 0) {
    start_note_ = "progress record without its .part file; restarted";
    return false;
  }
  chunk_bytes_ = chunk_bytes;
  const size_t count = remote_.size == 0 ? 0 : (remote_.size + chunk_bytes_ - 1) / chunk_bytes_;
  have_.assign(count, false);
  digests_.assign(count, std::string());
  missing_chunks_ = count;
  // Re-verify every recorded chunk from disk: the record may be ahead of the data after a
  // crash, or the .part may have been damaged.
  for (const auto& [index, digest] : chunks) {
    if (index >= count) continue;
    std::string actual;
    try {
      actual = auv::transfer::sha256OfRange(fd_, chunkOffset(index), chunkLength(index),
                                            partPath(final_path_).string());
    } catch (const std::exception&) {
      actual.clear();
    }
    if (actual == digest) {
      have_[index] = true;
      digests_[index] = digest;
      --missing_chunks_;
      ++reused_chunks_;
    } else {
      ++dropped_chunks_;
    }
  }
  if (::ftruncate(fd_, static_cast<off_t>(remote_.size)) != 0) {
    ioError(partPath(final_path_), "cannot size");
  }
  record_fd_ = ::open(progressPath(final_path_).c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
  if (record_fd_ < 0) ioError(progressPath(final_path_), "cannot open");
  if (text.size() != fs::file_size(progressPath(final_path_))) {
    // Drop the cut last line so new lines start clean.
    if (::ftruncate(record_fd_, static_cast<off_t>(text.size())) != 0) {
      ioError(progressPath(final_path_), "cannot trim");
    }
  }
  return true;
}

void PartialFile::startFresh() {
  if (fd_ >= 0) ::close(fd_);
  if (record_fd_ >= 0) ::close(record_fd_);
  const fs::path part = partPath(final_path_);
  fd_ = ::open(part.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) ioError(part, "cannot create");
  if (::ftruncate(fd_, static_cast<off_t>(remote_.size)) != 0) ioError(part, "cannot size");
  const fs::path record = progressPath(final_path_);
  record_fd_ = ::open(record.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_APPEND | O_CLOEXEC, 0644);
  if (record_fd_ < 0) ioError(record, "cannot create");
  const size_t count = remote_.size == 0 ? 0 : (remote_.size + chunk_bytes_ - 1) / chunk_bytes_;
  have_.assign(count, false);
  digests_.assign(count, std::string());
  missing_chunks_ = count;
  reused_chunks_ = 0;
  dropped_chunks_ = 0;
  whole_.reset();
  hashed_to_ = 0;
  appendRecord(std::string(kMagic) + "\nfile " + remote_.path + "\nsize " +
               std::to_string(remote_.size) + "\nsha256 " + remote_.sha256 + "\nchunk_bytes " +
               std::to_string(chunk_bytes_) + "\n");
}

void PartialFile::appendRecord(const std::string& line) {
  const size_t written = static_cast<size_t>(::write(record_fd_, line.data(), line.size()));
  if (written != line.size()) ioError(progressPath(final_path_), "cannot append");
}

void PartialFile::writeChunk(size_t index, const uint8_t* data, size_t size,
                             const std::string& sha256) {
  if (index >= have_.size() || size != chunkLength(index)) {
    throw std::logic_error("chunk " + std::to_string(index) + " of " + remote_.path +
                           ": wrong index or length");
  }
  if (have_[index]) return;
  writeAll(fd_, data, size, chunkOffset(index), partPath(final_path_));
  // Data first, then its record line: a record never names a chunk that was not written
  // (and a resumed pull re-verifies anyway, in case the data never reached the disk).
  appendRecord("chunk " + std::to_string(index) + " " + sha256 + "\n");
  have_[index] = true;
  digests_[index] = sha256;
  --missing_chunks_;
  advanceWholeDigest(data, index);
}

void PartialFile::advanceWholeDigest(const uint8_t* written, size_t index) {
  if (!whole_) whole_ = std::make_unique<auv::transfer::Sha256>();
  if (chunkOffset(index) == hashed_to_) {
    // The usual case: the chunk that continues the digest, still in the caller's buffer.
    whole_->update(written, chunkLength(index));
    hashed_to_ += chunkLength(index);
  }
  // Chunks that arrived ahead of it and are now contiguous: read back (page cache).
  size_t next = static_cast<size_t>(hashed_to_ / chunk_bytes_);
  std::vector<uint8_t> buffer;
  while (hashed_to_ < remote_.size && hashed_to_ % chunk_bytes_ == 0 && next < have_.size() &&
         have_[next]) {
    buffer.resize(chunkLength(next));
    size_t done = 0;
    while (done < buffer.size()) {
      const ssize_t n = ::pread(fd_, buffer.data() + done, buffer.size() - done,
                                static_cast<off_t>(hashed_to_ + done));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) ioError(partPath(final_path_), "read back failed");
      done += static_cast<size_t>(n);
    }
    whole_->update(buffer.data(), buffer.size());
    hashed_to_ += buffer.size();
    ++next;
  }
}

std::vector<size_t> PartialFile::finish() {
  if (!allChunks()) throw std::logic_error(remote_.path + ": finish() with chunks missing");
  const fs::path part = partPath(final_path_);
  // The digest so far covers [0, hashed_to_); the rest (chunks reused on resume) is read.
  if (!whole_) whole_ = std::make_unique<auv::transfer::Sha256>();
  std::string actual;
  if (hashed_to_ < remote_.size) {
    const uint64_t rest = remote_.size - hashed_to_;
    std::vector<uint8_t> buffer(static_cast<size_t>(std::min<uint64_t>(rest, 1u << 20)));
    for (uint64_t at = hashed_to_; at < remote_.size;) {
      const size_t want = static_cast<size_t>(std::min<uint64_t>(buffer.size(), remote_.size - at));
      const ssize_t n = ::pread(fd_, buffer.data(), want, static_cast<off_t>(at));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) ioError(part, "read back failed");
      whole_->update(buffer.data(), static_cast<size_t>(n));
      at += static_cast<uint64_t>(n);
    }
    hashed_to_ = remote_.size;
  }
  actual = whole_->hexDigest();
  whole_.reset();
  if (actual != remote_.sha256) {
    // Which chunks? Each against the digest it was recorded with (one more pass, only here).
    std::vector<size_t> bad;
    for (size_t i = 0; i < have_.size(); ++i) {
      std::string chunk;
      try {
        chunk = auv::transfer::sha256OfRange(fd_, chunkOffset(i), chunkLength(i), part.string());
      } catch (const std::exception&) {
        chunk.clear();
      }
      if (chunk != digests_[i]) bad.push_back(i);
    }
    if (!bad.empty()) {
      for (size_t i : bad) {
        have_[i] = false;
        ++missing_chunks_;
      }
      hashed_to_ = 0;  // digested again from the start once the chunks are back
      return bad;
    }
    discard();
    throw VerifyError(remote_.path + ": SHA-256 of the pulled file is " + actual +
                      ", the vehicle catalogued " + remote_.sha256 + "; partial file discarded");
  }
  if (::fsync(fd_) != 0) ioError(part, "fsync failed");
  ::close(fd_);
  fd_ = -1;
  std::error_code error;
  fs::rename(part, final_path_, error);
  if (error) throw std::runtime_error(part.string() + ": cannot rename: " + error.message());
  syncFolder(final_path_.parent_path());
  ::close(record_fd_);
  record_fd_ = -1;
  fs::remove(progressPath(final_path_), error);
  return {};
}

void PartialFile::discard() {
  if (fd_ >= 0) ::close(fd_);
  if (record_fd_ >= 0) ::close(record_fd_);
  fd_ = record_fd_ = -1;
  std::error_code error;
  fs::remove(partPath(final_path_), error);
  fs::remove(progressPath(final_path_), error);
}

}  // namespace auv::recon::transfer
