#include "auv/transfer/chunk_reader.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace fs = std::filesystem;

namespace auv::transfer {

void checkRelativePath(const std::string& relative) {
  auto bad = [&](const std::string& why) {
    throw ChunkError(ChunkError::Kind::INVALID_PATH, "file_path '" + relative + "': " + why);
  };
  if (relative.empty()) bad("empty");
  if (relative.size() > 4096) bad("longer than 4096 bytes");
  if (relative.front() == '/') bad("absolute; paths are relative to the recordings root");
  if (relative.find('\0') != std::string::npos) bad("contains a NUL byte");
  if (relative.find('\\') != std::string::npos) bad("contains '\\'; use '/'");
  size_t start = 0;
  while (start <= relative.size()) {
    const size_t end = std::min(relative.find('/', start), relative.size());
    const std::string element = relative.substr(start, end - start);
    if (element.empty()) bad("empty path element");
    if (element == "." || element == "..") bad("'" + element + "' is not allowed");
    start = end + 1;
  }
}

ChunkReader::ChunkReader(fs::path root, uint32_t max_chunk_bytes)
    : root_(std::move(root)), max_chunk_bytes_(max_chunk_bytes) {
  if (max_chunk_bytes_ == 0) throw std::invalid_argument("max_chunk_bytes: must be > 0");
  std::error_code error;
  const fs::path canonical = fs::canonical(root_, error);
  if (!error) root_ = canonical;
}

fs::path ChunkReader::resolve(const std::string& relative) const {
  checkRelativePath(relative);
  std::error_code error;
  const fs::path root = fs::canonical(root_, error);
  if (error) {
    throw ChunkError(ChunkError::Kind::NOT_FOUND,
                     "file_path '" + relative + "': the recordings root does not exist");
  }
  const fs::path resolved = fs::canonical(root / relative, error);
  if (error)
    throw ChunkError(ChunkError::Kind::NOT_FOUND, "file_path '" + relative + "': no such file");
  // Lexically clean already; a symlink inside the root may still point out of it.
  const std::string inside = resolved.string();
  const std::string prefix = root.string() == "/" ? "/" : root.string() + "/";
  if (inside.compare(0, prefix.size(), prefix) != 0) {
    throw ChunkError(ChunkError::Kind::NOT_FOUND,
                     "file_path '" + relative + "': outside the recordings root");
  }
  return resolved;
}

Chunk ChunkReader::read(const std::string& relative, uint64_t offset, uint32_t length,
                        const std::optional<FileStamp>& expected) const {
  const fs::path path = resolve(relative);
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) {
    throw ChunkError(errno == ENOENT ? ChunkError::Kind::NOT_FOUND : ChunkError::Kind::IO,
                     "file_path '" + relative + "': cannot open: " + std::strerror(errno));
  }
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    throw ChunkError(ChunkError::Kind::NOT_FOUND,
                     "file_path '" + relative + "': not a regular file");
  }
  const FileStamp now{static_cast<uint64_t>(st.st_size),
                      static_cast<int64_t>(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec};
  if (expected && now != *expected) {
    throw ChunkError(ChunkError::Kind::CHANGED, "file_path '" + relative +
                                                    "': changed since it was catalogued (size " +
                                                    std::to_string(expected->size) + " -> " +
                                                    std::to_string(now.size) + " bytes)");
  }
  if (offset > now.size) {
    throw ChunkError(ChunkError::Kind::BAD_RANGE, "offset " + std::to_string(offset) +
                                                      " is past the end of '" + relative + "' (" +
                                                      std::to_string(now.size) + " bytes)");
  }
  Chunk chunk;
  chunk.total_size = now.size;
  const uint64_t wanted =
      std::min<uint64_t>({uint64_t{length}, uint64_t{max_chunk_bytes_}, now.size - offset});
  chunk.data.resize(static_cast<size_t>(wanted));
  size_t done = 0;
  while (done < wanted) {
    const ssize_t got =
        ::pread(fd, chunk.data.data() + done, wanted - done, static_cast<off_t>(offset + done));
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) {
      throw ChunkError(ChunkError::Kind::IO,
                       "file_path '" + relative + "': read error: " + std::strerror(errno));
    }
    if (got == 0) {
      throw ChunkError(ChunkError::Kind::CHANGED,
                       "file_path '" + relative + "': shrank while being read");
    }
    done += static_cast<size_t>(got);
  }
  return chunk;
}

}  // namespace auv::transfer
