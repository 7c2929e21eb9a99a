#include "auv/bag/mcap_writer.h"

#include <fcntl.h>
#include <stdio.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "auv/bag/bag_error.h"
#include "auv/bag/compression.h"

namespace auv::bag {

namespace fs = std::filesystem;

const config::OptionTable<McapWriterOptions>& McapWriterOptions::table() {
  using O = McapWriterOptions;
  static const config::OptionTable<O> kTable = {
      {"profile", &O::profile, "the Header's profile: empty, or a well-known one such as ros2"},
      {"library", &O::library, "the Header's library: who wrote the file"},
      {"compression", &O::compression, "chunk compression", "", {}, {"none", "zstd", "lz4"}},
      {"compression_level", &O::compression_level,
       "0: the default (zstd 1, lz4 fast); zstd 1-19, lz4 1-12 (3 and above: LZ4 HC)", "",
       config::Range::closed(0, 19)},
      {"chunk_size", &O::chunk_size, "records after which a chunk is compressed and written",
       "bytes", config::Range::closed(1024, 256.0 * 1024 * 1024)},
      {"overwrite", &O::overwrite, "replace an existing file instead of refusing"},
      {"fsync_chunks", &O::fsync_chunks, "fsync after each chunk (survives a power loss)"}};
  return kTable;
}

void McapWriterOptions::check() const {
  config::checkOptions(*this, table());
  if (compression == "lz4" && compression_level > 12) {
    throw std::invalid_argument("compression_level: expected an integer in [0, 12] for lz4, got " +
                                std::to_string(compression_level));
  }
}

McapWriter::McapWriter(McapWriterOptions options) : options_(std::move(options)) {
  options_.check();
}

McapWriter::~McapWriter() {
  if (!isOpen()) return;
  try {
    close();
  } catch (...) {  // a destructor cannot report; the `.part` file is left for recovery
    closeFile();
  }
}

void McapWriter::requireOpen(const char* what) const {
  if (!isOpen()) throw std::logic_error(std::string("McapWriter::") + what + ": no file open");
}

void McapWriter::open(const fs::path& path) {
  if (isOpen()) throw std::logic_error("McapWriter::open: '" + path_.string() + "' is open");
  path_ = path;
  part_path_ = path;
  part_path_ += ".part";
  std::error_code ignored;
  if (!options_.overwrite) {
    if (fs::exists(fs::symlink_status(path_, ignored))) {
      throw BagError(BagError::Kind::EXISTS,
                     "'" + path_.string() + "' exists; not overwriting it (choose another name)");
    }
    if (fs::exists(fs::symlink_status(part_path_, ignored))) {
      throw BagError(BagError::Kind::EXISTS,
                     "'" + part_path_.string() +
                         "' exists: an unfinished recording (another writer's, or one that "
                         "stopped without closing; McapReader reads its complete chunks); not "
                         "overwriting it");
    }
  }
  const int flags = O_WRONLY | O_CREAT | O_CLOEXEC | (options_.overwrite ? O_TRUNC : O_EXCL);
  fd_ = ::open(part_path_.c_str(), flags, 0644);
  if (fd_ < 0) {
    const int error = errno;
    throw BagError(error == EEXIST ? BagError::Kind::EXISTS : BagError::Kind::IO,
                   "cannot create '" + part_path_.string() + "': " + std::strerror(error));
  }
  offset_ = 0;
  whole_end_ = 0;
  data_crc_ = 0;
  schemas_.clear();
  channels_.clear();
  metadata_.clear();
  metadata_indexes_.clear();
  chunk_indexes_.clear();
  statistics_ = Statistics{};
  chunk_.clear();
  chunk_index_.clear();
  stats_ = WriterStats{};
  compressor_ = std::make_unique<Compressor>(options_.compression == "zstd"  ? Compression::ZSTD
                                             : options_.compression == "lz4" ? Compression::LZ4
                                                                             : Compression::NONE,
                                             options_.compression_level);
  chunk_.bytes().reserve(options_.chunk_size + options_.chunk_size / 8);

  RecordBuffer start;
  start.bytes().assign(kMagic, kMagic + kMagicSize);
  start.header(Header{options_.profile, options_.library});
  writeRecords(start);
}

void McapWriter::writeBytes(const uint8_t* data, size_t size, const uint32_t* crc) {
  const size_t total = size;
  while (size > 0) {
    const ssize_t n = ::write(fd_, data, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string why = n < 0 ? std::strerror(errno) : "nothing written";
      // The `.part` file keeps every record written before this one, and ends with the last
      // of them, not with a torn part of this one (shrinking works on a full disk).
      if (::ftruncate(fd_, static_cast<off_t>(whole_end_)) != 0) {
        // Still readable: the reader stops at the torn record and reports it.
      }
      closeFile();
      throw BagError(BagError::Kind::IO, "cannot write '" + part_path_.string() + "': " + why);
    }
    data += n;
    size -= static_cast<size_t>(n);
  }
  data_crc_ =
      crc ? crc32Combine(data_crc_, *crc, total) : crc32Update(data_crc_, data - total, total);
  offset_ += total;
  stats_.file_bytes = offset_;
}

void McapWriter::writeRecords(const RecordBuffer& records, bool whole) {
  writeBytes(records.bytes().data(), records.size());
  if (whole) whole_end_ = offset_;
}

uint16_t McapWriter::addSchema(const std::string& name, const std::string& encoding,
                               const std::string& data) {
  requireOpen("addSchema");
  for (const Schema& schema : schemas_) {
    if (schema.name == name && schema.encoding == encoding && schema.data == data) {
      return schema.id;
    }
  }
  if (schemas_.size() >= 0xFFFF) throw std::invalid_argument("addSchema: 65535 schemas already");
  Schema schema{static_cast<uint16_t>(schemas_.size() + 1), name, encoding, data};
  RecordBuffer record;
  record.schema(schema);
  writeRecords(record);  // outside chunks: a damaged chunk cannot take a schema with it
  schemas_.push_back(std::move(schema));
  return schemas_.back().id;
}

uint16_t McapWriter::addChannel(uint16_t schema_id, const std::string& topic,
                                const std::string& message_encoding, const StringMap& metadata) {
  requireOpen("addChannel");
  if (schema_id > schemas_.size()) {
    throw std::invalid_argument("addChannel: topic '" + topic + "': unknown schema id " +
                                std::to_string(schema_id));
  }
  for (const Channel& channel : channels_) {
    if (channel.schema_id == schema_id && channel.topic == topic &&
        channel.message_encoding == message_encoding && channel.metadata == metadata) {
      return channel.id;
    }
  }
  if (channels_.size() >= 0xFFFF) throw std::invalid_argument("addChannel: 65535 channels already");
  Channel channel{static_cast<uint16_t>(channels_.size() + 1), schema_id, topic, message_encoding,
                  metadata};
  RecordBuffer record;
  record.channel(channel);
  writeRecords(record);
  channels_.push_back(std::move(channel));
  statistics_.channel_message_counts[channels_.back().id] = 0;
  return channels_.back().id;
}

void McapWriter::write(uint16_t channel_id, uint32_t sequence, uint64_t log_time_ns,
                       uint64_t publish_time_ns, const uint8_t* data, size_t size) {
  requireOpen("write");
  if (channel_id == 0 || channel_id > channels_.size()) {
    throw std::invalid_argument("write: unknown channel id " + std::to_string(channel_id));
  }
  if (size > kMaxMessageBytes) {
    throw std::invalid_argument("write: a message of " + std::to_string(size) + " bytes on '" +
                                channels_[channel_id - 1].topic + "' is over the " +
                                std::to_string(kMaxMessageBytes) + " bytes a message may have");
  }
  const bool first = chunk_.size() == 0;
  chunk_index_[channel_id].entries.emplace_back(log_time_ns, chunk_.size());
  chunk_.message(channel_id, sequence, log_time_ns, publish_time_ns, data, size);
  chunk_start_ = first ? log_time_ns : std::min(chunk_start_, log_time_ns);
  chunk_end_ = first ? log_time_ns : std::max(chunk_end_, log_time_ns);

  Statistics& s = statistics_;
  s.message_start_time =
      s.message_count == 0 ? log_time_ns : std::min(s.message_start_time, log_time_ns);
  s.message_end_time =
      s.message_count == 0 ? log_time_ns : std::max(s.message_end_time, log_time_ns);
  ++s.message_count;
  ++s.channel_message_counts[channel_id];
  ++stats_.messages;
  if (chunk_.size() >= options_.chunk_size) writeChunk();
}

void McapWriter::writeChunk() {
  if (chunk_.size() == 0) return;
  const std::vector<uint8_t>& records = chunk_.bytes();
  ChunkHeader header;
  header.message_start_time = chunk_start_;
  header.message_end_time = chunk_end_;
  header.uncompressed_size = records.size();
  header.uncompressed_crc = crc32Update(0, records.data(), records.size());
  header.compression = compressionName(compressor_->compression());
  // Uncompressed chunks are written from the chunk itself, with the CRC already computed.
  const bool stored = compressor_->compression() == Compression::NONE;
  if (!stored) compressor_->compress(records.data(), records.size(), compressed_);
  const std::vector<uint8_t>& payload = stored ? records : compressed_;
  header.records_size = payload.size();

  ChunkIndex index;
  index.message_start_time = chunk_start_;
  index.message_end_time = chunk_end_;
  index.chunk_start_offset = offset_;
  index.compression = header.compression;
  index.compressed_size = payload.size();
  index.uncompressed_size = records.size();

  RecordBuffer prefix;
  prefix.chunkPrefix(header);
  index.chunk_length = prefix.size() + payload.size();
  // Message Index records, each channel's entries in log-time order (readers bisect them).
  RecordBuffer indexes;
  const uint64_t indexes_start = offset_ + index.chunk_length;
  for (auto& [channel, message_index] : chunk_index_) {
    message_index.channel_id = channel;
    std::stable_sort(message_index.entries.begin(), message_index.entries.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    index.message_index_offsets[channel] = indexes_start + indexes.size();
    indexes.messageIndex(message_index);
  }
  index.message_index_length = indexes.size();

  writeRecords(prefix, /*whole=*/false);  // the Chunk record's start: whole with its payload
  writeBytes(payload.data(), payload.size(), stored ? &header.uncompressed_crc : nullptr);
  whole_end_ = offset_;
  writeRecords(indexes);
  if (options_.fsync_chunks && ::fdatasync(fd_) != 0) {
    const std::string why = std::strerror(errno);
    closeFile();
    throw BagError(BagError::Kind::IO, "cannot fsync '" + part_path_.string() + "': " + why);
  }
  chunk_indexes_.push_back(std::move(index));
  ++stats_.chunks;
  stats_.uncompressed_bytes += records.size();
  chunk_.clear();
  chunk_index_.clear();
}

void McapWriter::flush() {
  requireOpen("flush");
  writeChunk();
}

void McapWriter::addMetadata(const std::string& name, const StringMap& metadata) {
  requireOpen("addMetadata");
  RecordBuffer record;
  record.metadata(Metadata{name, metadata});
  metadata_indexes_.push_back(MetadataIndex{offset_, record.size(), name});
  writeRecords(record);  // between chunks: Metadata records may not be inside one
  metadata_.push_back(Metadata{name, metadata});
}

void McapWriter::writeSummary() {
  // Grouped by opcode, each group found through a Summary Offset record; Channels precede the
  // Statistics that count their messages (the spec asks for both).
  RecordBuffer summary;
  const uint64_t summary_start = offset_;
  std::vector<SummaryOffset> groups;
  auto group = [&](Opcode opcode, auto&& add) {
    const size_t begin = summary.size();
    add();
    if (summary.size() > begin) {
      groups.push_back(SummaryOffset{static_cast<uint8_t>(opcode), summary_start + begin,
                                     summary.size() - begin});
    }
  };
  group(Opcode::SCHEMA, [&] {
    for (const Schema& schema : schemas_) summary.schema(schema);
  });
  group(Opcode::CHANNEL, [&] {
    for (const Channel& channel : channels_) summary.channel(channel);
  });
  statistics_.schema_count = static_cast<uint16_t>(schemas_.size());
  statistics_.channel_count = static_cast<uint32_t>(channels_.size());
  statistics_.metadata_count = static_cast<uint32_t>(metadata_.size());
  statistics_.chunk_count = static_cast<uint32_t>(chunk_indexes_.size());
  group(Opcode::STATISTICS, [&] { summary.statistics(statistics_); });
  group(Opcode::CHUNK_INDEX, [&] {
    for (const ChunkIndex& index : chunk_indexes_) summary.chunkIndex(index);
  });
  group(Opcode::METADATA_INDEX, [&] {
    for (const MetadataIndex& index : metadata_indexes_) summary.metadataIndex(index);
  });
  const uint64_t summary_offset_start = summary_start + summary.size();
  for (const SummaryOffset& offset : groups) summary.summaryOffset(offset);

  // The summary CRC covers the summary and the footer up to its own field.
  const size_t footer_at = summary.size();
  summary.footer(Footer{summary_start, summary_offset_start, 0});
  const size_t crc_end = footer_at + kRecordHeaderSize + 16;
  const uint32_t crc = crc32Update(0, summary.bytes().data(), crc_end);
  for (int i = 0; i < 4; ++i) summary.bytes()[crc_end + i] = static_cast<uint8_t>(crc >> (8 * i));
  summary.bytes().insert(summary.bytes().end(), kMagic, kMagic + kMagicSize);
  writeRecords(summary);
}

void McapWriter::close() {
  if (!isOpen()) return;
  writeChunk();
  RecordBuffer data_end;
  data_end.dataEnd(data_crc_);
  writeRecords(data_end);
  writeSummary();
  if (::fsync(fd_) != 0) {
    const std::string why = std::strerror(errno);
    closeFile();
    throw BagError(BagError::Kind::IO, "cannot fsync '" + part_path_.string() + "': " + why);
  }
  const int closed = ::close(fd_);
  fd_ = -1;
  if (closed != 0) {
    throw BagError(BagError::Kind::IO,
                   "cannot close '" + part_path_.string() + "': " + std::strerror(errno));
  }
  int renamed = -1;
  if (options_.overwrite) {
    renamed = ::rename(part_path_.c_str(), path_.c_str());
  } else {
    renamed = ::renameat2(AT_FDCWD, part_path_.c_str(), AT_FDCWD, path_.c_str(), RENAME_NOREPLACE);
    if (renamed != 0 && (errno == EINVAL || errno == ENOSYS)) {  // a file system without it
      std::error_code ignored;
      if (fs::exists(fs::symlink_status(path_, ignored))) {
        errno = EEXIST;
      } else {
        renamed = ::rename(part_path_.c_str(), path_.c_str());
      }
    }
  }
  if (renamed != 0) {
    const int error = errno;
    throw BagError(error == EEXIST ? BagError::Kind::EXISTS : BagError::Kind::IO,
                   "cannot rename '" + part_path_.string() + "' to '" + path_.string() +
                       "': " + std::strerror(error) + "; the recording is kept as '" +
                       part_path_.string() + "'");
  }
}

void McapWriter::closeFile() noexcept {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

}  // namespace auv::bag
