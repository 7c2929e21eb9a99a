#include "auv/bag/bag_info.h"

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <sstream>

namespace auv::bag {

Summary info(const std::filesystem::path& path, bool verify) {
  McapReader reader;
  reader.open(path);
  if (verify) reader.verify();
  Summary summary;
  summary.path = path.string();
  summary.file_size = reader.fileSize();
  summary.profile = reader.header().profile;
  summary.library = reader.header().library;
  summary.indexed = reader.indexed();
  summary.verified = verify;

  const Statistics& statistics = reader.statistics();
  summary.message_count = statistics.message_count;
  if (statistics.message_count > 0) {
    summary.start_ns = statistics.message_start_time;
    summary.end_ns = statistics.message_end_time;
    summary.duration_s = static_cast<double>(summary.end_ns - summary.start_ns) * 1e-9;
  }
  for (const auto& [id, channel] : reader.channels()) {
    ChannelSummary row;
    row.id = id;
    row.topic = channel.topic;
    row.message_encoding = channel.message_encoding;
    row.metadata = channel.metadata;
    const auto schema = reader.schemas().find(channel.schema_id);
    if (schema != reader.schemas().end()) {
      row.schema_name = schema->second.name;
      row.schema_encoding = schema->second.encoding;
    }
    const auto count = statistics.channel_message_counts.find(id);
    if (count != statistics.channel_message_counts.end()) row.message_count = count->second;
    summary.channels.push_back(std::move(row));
  }
  for (const ChunkIndex& chunk : reader.chunkIndexes()) {
    ++summary.chunk_compressions[chunk.compression.empty() ? "none" : chunk.compression];
    summary.compressed_bytes += chunk.compressed_size;
    summary.uncompressed_bytes += chunk.uncompressed_size;
  }
  summary.chunk_count = reader.chunkIndexes().size();
  summary.damaged_chunks = reader.damagedChunks();
  for (const Metadata& metadata : reader.metadata())
    summary.metadata_names.push_back(metadata.name);
  summary.attachment_count = reader.attachmentCount();
  summary.damage = reader.damage();
  return summary;
}

std::string formatTime(uint64_t ns) {
  char seconds[48];
  std::snprintf(seconds, sizeof(seconds), "%llu.%09llu",
                static_cast<unsigned long long>(ns / 1000000000ULL),
                static_cast<unsigned long long>(ns % 1000000000ULL));
  constexpr uint64_t kYear2000 = 946684800ULL * 1000000000ULL;
  if (ns < kYear2000) return std::string(seconds) + " s";
  const std::time_t t = static_cast<std::time_t>(ns / 1000000000ULL);
  std::tm utc{};
  gmtime_r(&t, &utc);
  char date[32];
  std::strftime(date, sizeof(date), "%Y-%m-%d %H:%M:%S", &utc);
  char text[96];
  std::snprintf(text, sizeof(text), "%s.%09llu UTC (%s)", date,
                static_cast<unsigned long long>(ns % 1000000000ULL), seconds);
  return text;
}

std::string formatBytes(uint64_t bytes) {
  static const char* kUnits[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  double value = static_cast<double>(bytes);
  int unit = 0;
  while (value >= 1024.0 && unit < 4) {
    value /= 1024.0;
    ++unit;
  }
  char text[32];
  if (unit == 0) {
    std::snprintf(text, sizeof(text), "%llu B", static_cast<unsigned long long>(bytes));
  } else {
    std::snprintf(text, sizeof(text), "%.1f %s", value, kUnits[unit]);
  }
  return text;
}

namespace {

std::string padded(const std::string& text, size_t width) {
  return text + std::string(width > text.size() ? width - text.size() : 0, ' ');
}

void writeChannels(std::ostringstream& out, const Summary& s) {
  size_t topic_width = 0;
  size_t count_width = 0;
  for (const ChannelSummary& c : s.channels) {
    topic_width = std::max(topic_width, c.topic.size());
    count_width = std::max(count_width, std::to_string(c.message_count).size());
  }
  for (const ChannelSummary& c : s.channels) {
    const std::string count = std::to_string(c.message_count);
    out << "  (" << c.id << ") " << padded(c.topic, topic_width) << "  "
        << std::string(count_width - count.size(), ' ') << count << " msgs  "
        << (c.schema_name.empty() ? "(no schema)" : c.schema_name);
    if (!c.schema_encoding.empty()) out << " [" << c.schema_encoding << "]";
    out << " " << c.message_encoding << "\n";
    for (const auto& [key, value] : c.metadata) {
      std::string shown = value;
      for (char& ch : shown) {
        if (ch == '\n') ch = ' ';
      }
      out << "        " << key << ": " << shown << "\n";
    }
  }
}

}  // namespace

std::string formatInfo(const Summary& s) {
  std::ostringstream out;
  out << "path:         " << s.path << "\n";
  out << "size:         " << formatBytes(s.file_size) << " (" << s.file_size << " bytes)\n";
  out << "library:      " << (s.library.empty() ? "(none)" : s.library) << "\n";
  out << "profile:      " << (s.profile.empty() ? "(none)" : s.profile) << "\n";
  out << "read from:    "
      << (s.indexed ? "the summary" : "a linear scan (no usable summary or index)") << "\n";
  out << "messages:     " << s.message_count << "\n";
  if (s.message_count > 0) {
    char duration[32];
    std::snprintf(duration, sizeof(duration), "%.3f s", s.duration_s);
    out << "start:        " << formatTime(s.start_ns) << "\n";
    out << "end:          " << formatTime(s.end_ns) << "\n";
    out << "duration:     " << duration << "\n";
  }
  out << "chunks:       " << s.chunk_count;
  if (!s.chunk_compressions.empty()) {
    out << " (";
    bool first = true;
    for (const auto& [name, count] : s.chunk_compressions) {
      out << (first ? "" : ", ") << name << ": " << count;
      first = false;
    }
    out << ")";
  }
  if (s.damaged_chunks > 0) out << ", " << s.damaged_chunks << " damaged";
  out << "\n";
  if (s.uncompressed_bytes > 0) {
    char ratio[32];
    std::snprintf(ratio, sizeof(ratio), "%.1f %%",
                  100.0 * static_cast<double>(s.compressed_bytes) /
                      static_cast<double>(s.uncompressed_bytes));
    out << "compression:  " << formatBytes(s.uncompressed_bytes) << " -> "
        << formatBytes(s.compressed_bytes) << " (" << ratio << ")\n";
  }
  out << "channels:     " << s.channels.size() << "\n";
  writeChannels(out, s);
  if (!s.metadata_names.empty()) {
    out << "metadata:    ";
    for (const std::string& name : s.metadata_names) out << " " << name;
    out << "\n";
  }
  if (s.attachment_count > 0) out << "attachments:  " << s.attachment_count << "\n";
  if (s.damage.empty()) {
    out << "damage:       none" << (s.verified ? " (every chunk and CRC checked)" : " found")
        << "\n";
  } else {
    out << "damage:       " << s.damage.size() << (s.damage.size() == 1 ? " place" : " places")
        << "\n";
    for (const Damage& d : s.damage) out << "  - " << d.text << "\n";
  }
  return out.str();
}

}  // namespace auv::bag
