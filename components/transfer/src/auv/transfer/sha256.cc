#include "auv/transfer/sha256.h"

#include <fcntl.h>
#include <openssl/evp.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <vector>

namespace auv::transfer {

struct Sha256::Context {
  EVP_MD_CTX* md = nullptr;
  ~Context() { EVP_MD_CTX_free(md); }
};

Sha256::Sha256() : context_(std::make_unique<Context>()) {
  context_->md = EVP_MD_CTX_new();
  if (context_->md == nullptr || EVP_DigestInit_ex(context_->md, EVP_sha256(), nullptr) != 1) {
    throw std::runtime_error("OpenSSL: cannot initialise SHA-256");
  }
}

Sha256::~Sha256() = default;

void Sha256::update(const void* data, size_t size) {
  if (size > 0 && EVP_DigestUpdate(context_->md, data, size) != 1) {
    throw std::runtime_error("OpenSSL: SHA-256 update failed");
  }
}

Sha256::Digest Sha256::digest() {
  Digest digest{};
  unsigned int length = 0;
  if (EVP_DigestFinal_ex(context_->md, digest.data(), &length) != 1 || length != digest.size()) {
    throw std::runtime_error("OpenSSL: SHA-256 final failed");
  }
  return digest;
}

std::string Sha256::hexDigest() { return toHex(digest()); }

std::string Sha256::toHex(const Digest& digest) {
  static const char kHex[] = "0123456789abcdef";
  std::string hex(2 * digest.size(), '0');
  for (size_t i = 0; i < digest.size(); ++i) {
    hex[2 * i] = kHex[digest[i] >> 4];
    hex[2 * i + 1] = kHex[digest[i] & 0xF];
  }
  return hex;
}

std::string Sha256::of(const void* data, size_t size) {
  Sha256 sha;
  sha.update(data, size);
  return sha.hexDigest();
}

std::string sha256OfRange(int fd, uint64_t offset, uint64_t length, const std::string& name) {
  Sha256 sha;
  std::vector<unsigned char> buffer(1 << 20);
  uint64_t done = 0;
  while (length == 0 || done < length) {
    size_t want = buffer.size();
    if (length != 0) want = static_cast<size_t>(std::min<uint64_t>(want, length - done));
    const ssize_t got = ::pread(fd, buffer.data(), want, static_cast<off_t>(offset + done));
    if (got < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error(name + ": read error: " + std::strerror(errno));
    }
    if (got == 0) {
      if (length == 0) break;
      throw std::runtime_error(name + ": file ends at " + std::to_string(offset + done) +
                               " bytes, expected " + std::to_string(offset + length));
    }
    sha.update(buffer.data(), static_cast<size_t>(got));
    done += static_cast<uint64_t>(got);
  }
  return sha.hexDigest();
}

std::string sha256OfFile(const std::filesystem::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw std::runtime_error(path.string() + ": cannot open: " + std::strerror(errno));
  try {
    std::string digest = sha256OfRange(fd, 0, 0, path.string());
    ::close(fd);
    return digest;
  } catch (...) {
    ::close(fd);
    throw;
  }
}

FileDigests sha256OfFileAndChunks(const std::filesystem::path& path, uint32_t chunk_bytes) {
  if (chunk_bytes == 0) throw std::invalid_argument("sha256OfFileAndChunks: chunk_bytes is 0");
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw std::runtime_error(path.string() + ": cannot open: " + std::strerror(errno));
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  FileDigests digests;
  Sha256 whole;
  auto piece = std::make_unique<Sha256>();
  uint32_t in_piece = 0;  // bytes of the current piece hashed so far
  std::vector<unsigned char> buffer(std::min<uint32_t>(chunk_bytes, 1u << 20));
  uint64_t offset = 0;
  for (;;) {
    const size_t want = std::min<size_t>(buffer.size(), chunk_bytes - in_piece);
    const ssize_t got = ::pread(fd, buffer.data(), want, static_cast<off_t>(offset));
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) throw std::runtime_error(path.string() + ": read error: " + std::strerror(errno));
    if (got == 0) break;
    whole.update(buffer.data(), static_cast<size_t>(got));
    piece->update(buffer.data(), static_cast<size_t>(got));
    offset += static_cast<uint64_t>(got);
    in_piece += static_cast<uint32_t>(got);
    if (in_piece == chunk_bytes) {
      digests.chunks.push_back(piece->digest());
      piece = std::make_unique<Sha256>();
      in_piece = 0;
    }
  }
  if (in_piece > 0) digests.chunks.push_back(piece->digest());
  digests.sha256 = whole.hexDigest();
  return digests;
}

bool isSha256Hex(const std::string& text) {
  if (text.size() != 64) return false;
  for (char c : text) {
    if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
  }
  return true;
}

}  // namespace auv::transfer
