#include "auv/config/state_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <utility>

namespace auv::config {
namespace fs = std::filesystem;

namespace {

[[noreturn]] void fail(const fs::path& path, const std::string& what, int error) {
  throw std::runtime_error(path.string() + ": cannot " + what + ": " + std::strerror(error));
}

/// Closes the descriptor on every path out.
class Descriptor {
 public:
  Descriptor(const fs::path& path, int flags, const char* what)
      : fd_(::open(path.c_str(), flags, 0644)) {
    if (fd_ < 0) fail(path, what, errno);
  }
  ~Descriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  Descriptor(const Descriptor&) = delete;
  Descriptor& operator=(const Descriptor&) = delete;
  int get() const { return fd_; }
  /// Closes now, so that a failing close is reported.
  int release() { return ::close(std::exchange(fd_, -1)); }

 private:
  int fd_;
};

}  // namespace

std::string launchId() {
  const char* id = std::getenv("AUV_LAUNCH_ID");
  return id ? id : "";
}

void writeFileAtomically(const fs::path& path, std::string_view data) {
  const fs::path folder = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec) fail(folder, "create the folder", ec.value());
  fs::path temporary = path;
  temporary += ".tmp";
  {
    Descriptor file(temporary, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, "write");
    for (size_t written = 0; written < data.size();) {
      const ssize_t n = ::write(file.get(), data.data() + written, data.size() - written);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) fail(temporary, "write", errno);
      written += static_cast<size_t>(n);
    }
    if (::fsync(file.get()) != 0) fail(temporary, "flush to disk", errno);
    if (file.release() != 0) fail(temporary, "close", errno);
  }
  if (::rename(temporary.c_str(), path.c_str()) != 0) fail(path, "replace", errno);
  // The rename itself is durable once the folder's entry is on disk.
  Descriptor directory(folder, O_RDONLY | O_DIRECTORY | O_CLOEXEC, "open the folder");
  if (::fsync(directory.get()) != 0) fail(folder, "flush the folder", errno);
}

}  // namespace auv::config
