#pragma once
// Chunk compression: zstd (a zstd frame) and lz4 (an LZ4 frame), the two MCAP names, and
// CRC-32 (zlib's, the polynomial MCAP uses). Decompression never trusts the sizes it is
// given: a frame that declares another size, or decodes to another size, is an error.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace auv::bag {

/// CRC-32 (IEEE 802.3, as zlib and MCAP compute it) of `size` bytes, continuing `crc`
/// (0 to start).
uint32_t crc32Update(uint32_t crc, const uint8_t* data, size_t size);
/// The CRC-32 of A followed by B from their CRCs and B's size (no pass over the bytes).
uint32_t crc32Combine(uint32_t crc_a, uint32_t crc_b, uint64_t size_b);

enum class Compression { NONE, ZSTD, LZ4 };

/// "" (none), "zstd" or "lz4": the name a Chunk record carries.
const char* compressionName(Compression compression);

/// Compresses chunks, keeping its compression context between calls.
class Compressor {
 public:
  /// `level`: 0 for our default (zstd 1, lz4's fast mode), else zstd 1..19 or lz4 1..12
  /// (3 and above: LZ4 HC).
  Compressor(Compression compression, int level);
  ~Compressor();
  Compressor(const Compressor&) = delete;
  Compressor& operator=(const Compressor&) = delete;

  /// Replaces `out` with the compressed `size` bytes of `data` (a copy for NONE); throws
  /// std::runtime_error if the library fails.
  void compress(const uint8_t* data, size_t size, std::vector<uint8_t>& out);
  Compression compression() const { return compression_; }

 private:
  struct Impl;
  Compression compression_;
  int level_;
  std::unique_ptr<Impl> impl_;
};

/// The `uncompressed_size` bytes `data` decompresses to with the chunk's `compression` name;
/// throws std::runtime_error saying why not (unknown name, bad frame, other size).
std::vector<uint8_t> decompress(const std::string& compression, const uint8_t* data, size_t size,
                                uint64_t uncompressed_size);

}  // namespace auv::bag
