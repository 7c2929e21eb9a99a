#pragma once
// SHA-256 through OpenSSL's EVP API, as lowercase hex: the digests of the recordings
// catalogue, of file chunks on the wire and of the shore's verified files.

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace auv::transfer {

/// Incremental SHA-256. Not copyable; digest() may be called once.
class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;

  using Digest = std::array<unsigned char, 32>;

  void update(const void* data, size_t size);
  /// Finishes and returns the 32 bytes.
  Digest digest();
  /// Finishes and returns 64 lowercase hex digits.
  std::string hexDigest();

  static std::string toHex(const Digest& digest);

  /// SHA-256 of one buffer.
  static std::string of(const void* data, size_t size);

 private:
  struct Context;
  std::unique_ptr<Context> context_;
};

/// SHA-256 of the bytes [offset, offset + length) of an open file (length 0: to the end).
/// Throws std::runtime_error naming `name` on a read error or a short file.
std::string sha256OfRange(int fd, uint64_t offset, uint64_t length, const std::string& name);

/// SHA-256 of a whole file; throws std::runtime_error naming the file.
std::string sha256OfFile(const std::filesystem::path& path);

/// A file's SHA-256 and those of its consecutive `chunk_bytes` pieces (the last one shorter).
struct FileDigests {
  std::string sha256;                  ///< whole file, hex
  std::vector<Sha256::Digest> chunks;  ///< piece i = bytes [i * chunk_bytes, (i + 1) * chunk_bytes)
};

/// Both in one read of the file (the recorder serves chunks with their digest, computed once
/// when the file is catalogued instead of at every request). Throws std::runtime_error naming
/// the file; std::invalid_argument for chunk_bytes 0.
FileDigests sha256OfFileAndChunks(const std::filesystem::path& path, uint32_t chunk_bytes);

/// True for 64 lowercase hex digits.
bool isSha256Hex(const std::string& text);

}  // namespace auv::transfer
