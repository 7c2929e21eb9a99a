#pragma once
// Little-endian binary reading/writing for the feature and match files (private to features/).

#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>

namespace auv::recon::features::internal {

/// Appends plain values to a byte string (the files are written whole, then atomically).
class ByteWriter {
 public:
  template <class T>
  void put(const T& value) {
    static_assert(std::is_trivially_copyable<T>::value, "plain values only");
    bytes_.append(reinterpret_cast<const char*>(&value), sizeof(T));
  }
  void putBytes(const void* data, size_t size) {
    bytes_.append(static_cast<const char*>(data), size);
  }
  void putString16(const std::string& text) {
    if (text.size() > 0xffff) throw std::runtime_error("name longer than 65535 bytes: " + text);
    put<uint16_t>(static_cast<uint16_t>(text.size()));
    bytes_.append(text);
  }
  const std::string& bytes() const { return bytes_; }

 private:
  std::string bytes_;
};

/// Reads plain values from a byte string; `what` names the file in errors.
class ByteReader {
 public:
  ByteReader(const std::string& bytes, std::string what) : bytes_(bytes), what_(std::move(what)) {}
  template <class T>
  T get() {
    T value;
    getBytes(&value, sizeof(T));
    return value;
  }
  void getBytes(void* out, size_t size) {
    if (size > bytes_.size() - offset_) {
      throw std::runtime_error(what_ + ": truncated (needs " + std::to_string(offset_ + size) +
                               " bytes, has " + std::to_string(bytes_.size()) + ")");
    }
    std::memcpy(out, bytes_.data() + offset_, size);
    offset_ += size;
  }
  std::string getString16() {
    const uint16_t length = get<uint16_t>();
    std::string text(length, '\0');
    getBytes(text.data(), length);
    return text;
  }
  size_t remaining() const { return bytes_.size() - offset_; }

 private:
  const std::string& bytes_;
  std::string what_;
  size_t offset_ = 0;
};

/// The whole file; throws std::runtime_error naming it when it cannot be read.
std::string readWholeFile(const std::string& path);

}  // namespace auv::recon::features::internal
