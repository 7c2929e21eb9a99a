#include "auv/bag/compression.h"

#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include <stdexcept>

namespace auv::bag {

uint32_t crc32Update(uint32_t crc, const uint8_t* data, size_t size) {
  return static_cast<uint32_t>(::crc32_z(crc, data, size));
}

uint32_t crc32Combine(uint32_t crc_a, uint32_t crc_b, uint64_t size_b) {
  return static_cast<uint32_t>(::crc32_combine64(crc_a, crc_b, static_cast<z_off64_t>(size_b)));
}

const char* compressionName(Compression compression) {
  switch (compression) {
    case Compression::ZSTD:
      return "zstd";
    case Compression::LZ4:
      return "lz4";
    case Compression::NONE:
      break;
  }
  return "";
}

struct Compressor::Impl {
  ZSTD_CCtx* zstd = nullptr;
  ~Impl() { ZSTD_freeCCtx(zstd); }
};

Compressor::Compressor(Compression compression, int level)
    : compression_(compression), level_(level), impl_(std::make_unique<Impl>()) {
  if (compression_ == Compression::ZSTD) {
    impl_->zstd = ZSTD_createCCtx();
    if (!impl_->zstd) throw std::runtime_error("zstd: cannot create a compression context");
  }
}

Compressor::~Compressor() = default;

void Compressor::compress(const uint8_t* data, size_t size, std::vector<uint8_t>& out) {
  switch (compression_) {
    case Compression::NONE:
      out.assign(data, data + size);
      return;
    case Compression::ZSTD: {
      // Level 1 by default: a recorder on the vehicle's shared cores wants speed first
      // (components/bag/bench/README.md has the figures).
      out.resize(ZSTD_compressBound(size));
      const size_t n = ZSTD_compressCCtx(impl_->zstd, out.data(), out.size(), data, size,
                                         level_ > 0 ? level_ : 1);
      if (ZSTD_isError(n)) throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(n));
      out.resize(n);
      return;
    }
    case Compression::LZ4: {
      LZ4F_preferences_t preferences = LZ4F_INIT_PREFERENCES;
      preferences.frameInfo.contentSize = size;  // lets a reader check the size it is told
      preferences.compressionLevel = level_;
      out.resize(LZ4F_compressFrameBound(size, &preferences));
      const size_t n = LZ4F_compressFrame(out.data(), out.size(), data, size, &preferences);
      if (LZ4F_isError(n)) throw std::runtime_error(std::string("lz4: ") + LZ4F_getErrorName(n));
      out.resize(n);
      return;
    }
  }
}

namespace {

std::vector<uint8_t> decompressZstd(const uint8_t* data, size_t size, uint64_t expected) {
  const unsigned long long declared = ZSTD_getFrameContentSize(data, size);
  if (declared == ZSTD_CONTENTSIZE_ERROR) throw std::runtime_error("zstd: not a zstd frame");
  if (declared != ZSTD_CONTENTSIZE_UNKNOWN && declared != expected) {
    throw std::runtime_error("zstd: the frame holds " + std::to_string(declared) +
                             " bytes, the chunk says " + std::to_string(expected));
  }
  std::vector<uint8_t> out(expected);
  const size_t n = ZSTD_decompress(out.data(), out.size(), data, size);
  if (ZSTD_isError(n)) throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(n));
  if (n != expected) {
    throw std::runtime_error("zstd: decoded " + std::to_string(n) + " bytes, the chunk says " +
                             std::to_string(expected));
  }
  return out;
}

std::vector<uint8_t> decompressLz4(const uint8_t* data, size_t size, uint64_t expected) {
  LZ4F_dctx* context = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&context, LZ4F_VERSION))) {
    throw std::runtime_error("lz4: cannot create a decompression context");
  }
  struct Free {
    LZ4F_dctx* c;
    ~Free() { LZ4F_freeDecompressionContext(c); }
  } free_context{context};

  LZ4F_frameInfo_t info{};
  size_t consumed = size;
  size_t hint = LZ4F_getFrameInfo(context, &info, data, &consumed);
  if (LZ4F_isError(hint)) throw std::runtime_error(std::string("lz4: ") + LZ4F_getErrorName(hint));
  if (info.contentSize != 0 && info.contentSize != expected) {
    throw std::runtime_error("lz4: the frame holds " + std::to_string(info.contentSize) +
                             " bytes, the chunk says " + std::to_string(expected));
  }
  std::vector<uint8_t> out(expected);
  size_t in_at = consumed;
  size_t out_at = 0;
  while (hint != 0) {
    size_t in_size = size - in_at;
    size_t out_size = out.size() - out_at;
    if (in_size == 0) throw std::runtime_error("lz4: the frame ends early");
    hint =
        LZ4F_decompress(context, out.data() + out_at, &out_size, data + in_at, &in_size, nullptr);
    if (LZ4F_isError(hint))
      throw std::runtime_error(std::string("lz4: ") + LZ4F_getErrorName(hint));
    in_at += in_size;
    out_at += out_size;
    if (hint != 0 && in_size == 0 && out_size == 0) {
      throw std::runtime_error("lz4: the frame decodes to more than " + std::to_string(expected) +
                               " bytes");
    }
  }
  if (out_at != expected) {
    throw std::runtime_error("lz4: decoded " + std::to_string(out_at) + " bytes, the chunk says " +
                             std::to_string(expected));
  }
  if (in_at != size) {
    throw std::runtime_error("lz4: " + std::to_string(size - in_at) +
                             " bytes after the end of the frame");
  }
  return out;
}

}  // namespace

std::vector<uint8_t> decompress(const std::string& compression, const uint8_t* data, size_t size,
                                uint64_t uncompressed_size) {
  if (compression.empty()) {
    if (size != uncompressed_size) {
      throw std::runtime_error("uncompressed chunk of " + std::to_string(size) +
                               " bytes says it holds " + std::to_string(uncompressed_size));
    }
    return std::vector<uint8_t>(data, data + size);
  }
  if (compression == "zstd") return decompressZstd(data, size, uncompressed_size);
  if (compression == "lz4") return decompressLz4(data, size, uncompressed_size);
  throw std::runtime_error("unknown compression '" + compression + "'");
}

}  // namespace auv::bag
