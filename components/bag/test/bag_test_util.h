#pragma once
// Shared pieces of the auv_bag tests: temporary folders, bags with known content, file bytes.

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "auv/bag/mcap_reader.h"
#include "auv/bag/mcap_writer.h"

namespace auv::bag::testing {

namespace fs = std::filesystem;

/// A fresh folder under the system temp dir, removed with the object.
class TempDir {
 public:
  explicit TempDir(const std::string& tag) {
    path_ = fs::temp_directory_path() /
            ("auv_bag_" + tag + "_" + std::to_string(::getpid()) + "_" +
             std::to_string(std::chrono::steady_clock::now().time_since_epoch().count()));
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

/// A message as written, to compare with what is read.
struct Written {
  std::string topic;
  uint32_t sequence = 0;
  uint64_t log_time = 0;
  uint64_t publish_time = 0;
  std::vector<uint8_t> data;
};

inline bool operator==(const Written& a, const Written& b) {
  return a.topic == b.topic && a.sequence == b.sequence && a.log_time == b.log_time &&
         a.publish_time == b.publish_time && a.data == b.data;
}

inline std::ostream& operator<<(std::ostream& out, const Written& w) {
  return out << w.topic << "#" << w.sequence << "@" << w.log_time << " (" << w.data.size()
             << " bytes)";
}

inline Written asWritten(const BagMessage& m) {
  return Written{m.channel->topic, m.message.sequence, m.message.log_time, m.message.publish_time,
                 m.message.data};
}

inline std::vector<Written> asWritten(const std::vector<BagMessage>& messages) {
  std::vector<Written> out;
  for (const BagMessage& m : messages) out.push_back(asWritten(m));
  return out;
}

/// `size` pseudo-random bytes; `compressible` repeats a short pattern with a little noise.
inline std::vector<uint8_t> payload(size_t size, uint32_t seed, bool compressible = true) {
  std::mt19937 generator(seed);
  std::vector<uint8_t> bytes(size);
  for (size_t i = 0; i < size; ++i) {
    bytes[i] = compressible && generator() % 8 != 0 ? static_cast<uint8_t>(i % 17)
                                                    : static_cast<uint8_t>(generator());
  }
  return bytes;
}

/// Interleaved messages on `topics` topics: message i on topic i % topics at log time
/// base + i * step ns, sizes from 0 to max_size bytes.
inline std::vector<Written> someMessages(size_t count, size_t topics, size_t max_size,
                                         uint32_t seed = 1, uint64_t base = 1000,
                                         uint64_t step = 1000) {
  std::mt19937 generator(seed);
  std::vector<Written> out;
  for (size_t i = 0; i < count; ++i) {
    Written w;
    w.topic = "/topic_" + std::to_string(i % topics);
    w.sequence = static_cast<uint32_t>(i / topics);
    w.log_time = base + i * step;
    w.publish_time = w.log_time - 7;
    w.data = payload(generator() % (max_size + 1), seed * 7919 + static_cast<uint32_t>(i));
    out.push_back(std::move(w));
  }
  return out;
}

/// Writes `messages` to `path` (one channel per topic, schema "auv_msgs::msg::Blob" in OMG
/// IDL, QoS in the metadata, a Metadata record) and closes it.
inline void writeBag(const fs::path& path, const std::vector<Written>& messages,
                     McapWriterOptions options = {}) {
  McapWriter writer(options);
  writer.open(path);
  const uint16_t schema = writer.addSchema("auv_msgs::msg::Blob", "omgidl",
                                           "module auv_msgs { module msg { struct Blob { "
                                           "sequence<octet> data; }; }; };");
  std::map<std::string, uint16_t> channels;
  for (const Written& w : messages) {
    if (!channels.count(w.topic)) {
      channels[w.topic] = writer.addChannel(schema, w.topic, "cdr",
                                            {{"offered_qos_profiles", "reliable, keep last 10"}});
    }
    writer.write(channels[w.topic], w.sequence, w.log_time, w.publish_time, w.data);
  }
  writer.addMetadata("recording", {{"vehicle", "sparus"}, {"mission", "canyon"}});
  writer.close();
}

inline std::vector<uint8_t> readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), {});
}

inline void writeFile(const fs::path& path, const uint8_t* data, size_t size) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
}

/// Messages in log-time order, ties in the order written (what the reader must give).
inline std::vector<Written> inTimeOrder(std::vector<Written> messages) {
  std::stable_sort(messages.begin(), messages.end(),
                   [](const Written& a, const Written& b) { return a.log_time < b.log_time; });
  return messages;
}

inline std::string damageText(const McapReader& reader) {
  std::string text;
  for (const Damage& d : reader.damage()) text += d.text + "\n";
  return text;
}

}  // namespace auv::bag::testing
