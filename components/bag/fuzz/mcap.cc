// Fuzz harness: MCAP files as `auv bag info` and `auv bag play` read them, ours and other
// writers', whole or truncated or damaged: McapReader opens the file (summary, or the linear
// scan that recovers a damaged one), every message is read in log-time order, with and without
// a filter, and every chunk is verified; bag::info summarises it and formatInfo prints it; a
// Player takes its channels (topic names, schemas, the QoS kept in their metadata) as it does
// before it joins a domain. The bytes are a file in memory (memfd), as the reader takes paths.
// A clear error is a BagError from opening (not MCAP, unreadable) and the Player's
// std::invalid_argument for a channel it cannot play; damage is reported as values. Anything
// else (another exception, a crash, a sanitizer report) is a bug.
#include <sys/mman.h>
#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "auv/bag/bag_error.h"
#include "auv/bag/bag_info.h"
#include "auv/bag/dds/player.h"
#include "auv/bag/dds/qos_metadata.h"
#include "auv/bag/mcap_reader.h"
#include "auv/bag/mcap_writer.h"
#include "auv/interfaces/serialized.h"
#include "auv/msg/all.h"

namespace {

namespace fs = std::filesystem;
using auv::bag::BagError;
using auv::bag::McapReader;

// One in-memory file, rewritten for each input; readers open it by its /proc path.
class MemoryFile {
 public:
  MemoryFile() : fd_(::memfd_create("auv_fuzz_mcap", MFD_CLOEXEC)) {
    if (fd_ < 0) throw std::runtime_error("memfd_create failed");
  }
  ~MemoryFile() { ::close(fd_); }
  std::string write(const uint8_t* data, size_t size) {
    if (::ftruncate(fd_, 0) != 0) throw std::runtime_error("ftruncate failed");
    for (size_t done = 0; done < size;) {
      const ssize_t n = ::pwrite(fd_, data + done, size - done, static_cast<off_t>(done));
      if (n <= 0) throw std::runtime_error("pwrite failed");
      done += static_cast<size_t>(n);
    }
    return "/proc/self/fd/" + std::to_string(fd_);
  }

 private:
  int fd_;
};

// Reads every message's bytes, so that a sanitizer sees a read out of bounds.
void readAll(auv::bag::MessageIterator messages) {
  static volatile uint64_t sink = 0;  // keeps the reads
  while (auto message = messages.next()) {
    for (uint8_t byte : message->message.data) sink = sink + byte;
    sink = sink + message->channel->topic.size();
    if (message->schema) sink = sink + message->schema->data.size();
  }
}

void readBag(const std::string& path) {
  McapReader reader;
  try {
    reader.open(path);
  } catch (const BagError&) {
    return;
  }
  readAll(reader.messages());
  // A filter as `auv bag play --topics` and a start offset give: one topic, a later start.
  if (!reader.channels().empty()) {
    auv::bag::ReadFilter filter;
    filter.topics = {reader.channels().begin()->second.topic};
    const auto& statistics = reader.statistics();
    filter.start_ns = statistics.message_start_time / 2 + statistics.message_end_time / 2;
    readAll(reader.messages(filter));
  }
  reader.verify();
  readAll(reader.messages());  // after verify() has marked the damaged chunks
}

void bagInfo(const std::string& path) {
  try {
    const auv::bag::Summary summary = auv::bag::info(path, /*verify=*/true);
    auv::bag::formatInfo(summary);
  } catch (const BagError&) {
  }
}

void preparePlay(const std::string& path) {
  auv::bag::PlayerOptions options;
  options.input = path;
  try {
    auv::bag::Player player(options);
    player.playing();
  } catch (const BagError&) {
  } catch (const std::invalid_argument&) {
  }
}

// ---- seeds

// A folder under the temp dir for the writer's files, removed with the object.
class ScratchDir {
 public:
  ScratchDir() {
    std::string pattern = (fs::temp_directory_path() / "auv_fuzz_mcap_XXXXXX").string();
    if (::mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
    path_ = pattern;
  }
  ~ScratchDir() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

std::string readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// The CDR of `sample` as a typed writer sends it (what a recorder stores).
template <class T>
std::vector<uint8_t> cdrOf(const T& sample) {
  const auv::msg::TypeSupport& type =
      auv::interfaces::typeSupportByName(auv::msg::MessageTraits<T>::kTypeName);
  std::unique_ptr<eprosima::fastdds::dds::TopicDataType> typed(type.make_topic_data_type());
  void* data = const_cast<T*>(&sample);
  eprosima::fastrtps::rtps::SerializedPayload_t payload(typed->getSerializedSizeProvider(data)());
  if (!typed->serialize(data, &payload)) throw std::runtime_error("serialize " + type.name);
  return std::vector<uint8_t>(payload.data, payload.data + payload.length);
}

// A channel's metadata as the recorder writes it, for one writer of `type` with `qos`.
auv::bag::StringMap recordedMetadata(const std::string& type, auv::interfaces::QosProfile qos) {
  auv::interfaces::EndpointInfo writer;
  writer.type = type;
  writer.is_writer = true;
  writer.qos = qos;
  writer.history_known = true;
  writer.guid[0] = 0x01;  // a Cyclone DDS GUID prefix
  writer.guid[1] = 0x10;
  return auv::bag::channelMetadata(type, {writer}, qos);
}

// A small recording in `compression`: a keyed map topic and a text topic, messages spread over
// several chunks, and a Metadata record. `closed` false: the `.part` file of a recorder that
// stopped without closing, as the reader recovers it.
std::string recording(const fs::path& dir, const std::string& compression, bool closed) {
  auv::bag::McapWriterOptions options;
  options.compression = compression;
  options.chunk_size = 1024;  // the smallest: a few messages per chunk
  const fs::path path = dir / ("seed_" + compression + (closed ? ".mcap" : "_open.mcap"));
  auv::bag::McapWriter writer(options);
  writer.open(path);
  const auto& map_type = auv::interfaces::typeSupportByName("auv::msg::OctomapUpdate");
  const auto& text_type = auv::interfaces::typeSupportByName("auv::msg::String");
  const uint16_t map_schema = writer.addSchema(map_type.name, "omgidl", map_type.omg_idl);
  const uint16_t text_schema = writer.addSchema(text_type.name, "omgidl", text_type.omg_idl);
  const uint16_t map_channel = writer.addChannel(
      map_schema, "/map/update", "cdr", recordedMetadata(map_type.name, auv::interfaces::mapQos()));
  const uint16_t text_channel =
      writer.addChannel(text_schema, "/chatter", "cdr",
                        recordedMetadata(text_type.name, auv::interfaces::commandQos()));
  for (uint32_t i = 1; i <= 8; ++i) {
    const uint64_t t = 1'000'000'000ull * i;
    auv::msg::String text;
    text.data("line " + std::to_string(i));
    writer.write(text_channel, i, t, t - 1000, cdrOf(text));
    auv::msg::OctomapUpdate map;
    map.map_id("octomap");
    map.sequence_number(i);
    map.data(std::vector<uint8_t>(100 * i, static_cast<uint8_t>(i)));
    writer.write(map_channel, i, t + 500, t, cdrOf(map));
  }
  writer.addMetadata("recording", {{"vehicle", "sparus"}, {"mission", "breakwater"}});
  if (!closed) {
    writer.flush();
    return readFile(path.string() + ".part");
  }
  writer.close();
  return readFile(path);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static MemoryFile file;
  const std::string path = file.write(data, size);
  readBag(path);
  bagInfo(path);
  preparePlay(path);
  return 0;
}

/// Recordings by the project's writer: each compression, closed and left open.
std::vector<std::string> auvFuzzSeeds() {
  ScratchDir dir;
  std::vector<std::string> seeds;
  for (const char* compression : {"none", "zstd", "lz4"}) {
    seeds.push_back(recording(dir.path(), compression, true));
    seeds.push_back(recording(dir.path(), compression, false));
  }
  return seeds;
}
