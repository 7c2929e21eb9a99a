#include "auv/bag/mcap_reader.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "auv/bag/bag_error.h"
#include "auv/bag/compression.h"
#include "auv/bag/record_scan.h"

namespace auv::bag {

namespace {

std::string str(uint64_t value) { return std::to_string(value); }

/// The first field in which a Chunk record's header and its Chunk Index disagree, or "".
std::string disagreement(const ChunkHeader& header, const ChunkIndex& index) {
  if (header.compression != index.compression) {
    return "compression '" + header.compression + "' against '" + index.compression + "'";
  }
  if (header.records_size != index.compressed_size) {
    return "compressed size " + str(header.records_size) + " against " + str(index.compressed_size);
  }
  if (header.uncompressed_size != index.uncompressed_size) {
    return "uncompressed size " + str(header.uncompressed_size) + " against " +
           str(index.uncompressed_size);
  }
  if (header.message_start_time != index.message_start_time ||
      header.message_end_time != index.message_end_time) {
    return "message times [" + str(header.message_start_time) + ", " +
           str(header.message_end_time) + "] against [" + str(index.message_start_time) + ", " +
           str(index.message_end_time) + "]";
  }
  return "";
}

}  // namespace

McapReader::McapReader() = default;

McapReader::~McapReader() {
  if (fd_ >= 0) ::close(fd_);
}

std::vector<uint8_t> McapReader::readAt(uint64_t offset, uint64_t size) const {
  if (offset > size_ || size > size_ - offset) {  // callers check first; this is the last guard
    throw BagError(BagError::Kind::IO, "'" + path_.string() + "': read of " + str(size) +
                                           " bytes at byte " + str(offset) + " past its end");
  }
  std::vector<uint8_t> bytes(size);
  uint64_t done = 0;
  while (done < size) {
    const ssize_t n = ::pread(fd_, bytes.data() + done, size - done, offset + done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      throw BagError(BagError::Kind::IO,
                     "cannot read '" + path_.string() + "' at byte " + str(offset + done) + ": " +
                         (n < 0 ? std::strerror(errno) : "the file got shorter while reading"));
    }
    done += static_cast<uint64_t>(n);
  }
  return bytes;
}

uint32_t McapReader::crcOfRange(uint32_t crc, uint64_t offset, uint64_t size) const {
  constexpr uint64_t kBlock = 1 << 20;
  for (uint64_t at = 0; at < size; at += kBlock) {
    const std::vector<uint8_t> block = readAt(offset + at, std::min(kBlock, size - at));
    crc = crc32Update(crc, block.data(), block.size());
  }
  return crc;
}

void McapReader::addDamage(uint64_t offset, const std::string& text) {
  damage_.push_back(Damage{offset, text});
}

size_t McapReader::damagedChunks() const {
  return static_cast<size_t>(
      std::count(chunk_states_.begin(), chunk_states_.end(), ChunkState::DAMAGED));
}

void McapReader::open(const std::filesystem::path& path) {
  if (fd_ >= 0) throw std::logic_error("McapReader::open: '" + path_.string() + "' is open");
  path_ = path;
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) {
    const int error = errno;
    throw BagError(error == ENOENT ? BagError::Kind::NOT_FOUND : BagError::Kind::IO,
                   "cannot open '" + path.string() + "': " + std::strerror(error));
  }
  struct stat status {};
  if (::fstat(fd_, &status) != 0 || !S_ISREG(status.st_mode)) {
    throw BagError(BagError::Kind::NOT_MCAP, "'" + path.string() + "' is not a regular file");
  }
  size_ = static_cast<uint64_t>(status.st_size);
  if (size_ < kMagicSize) {
    throw BagError(BagError::Kind::NOT_MCAP, "'" + path.string() + "' is not an MCAP file: " +
                                                 str(size_) + " bytes, fewer than its magic");
  }
  if (std::memcmp(readAt(0, kMagicSize).data(), kMagic, kMagicSize) != 0) {
    throw BagError(BagError::Kind::NOT_MCAP,
                   "'" + path.string() +
                       "' is not an MCAP file: it does not begin with the "
                       "MCAP magic");
  }

  uint64_t data_start = kMagicSize;
  if (size_ - kMagicSize < kRecordHeaderSize) {
    addDamage(size_, "truncated at byte " + str(size_) + ": no Header record after the magic");
    return;
  }
  const std::vector<uint8_t> head = readAt(kMagicSize, kRecordHeaderSize);
  const uint64_t length = readU64(&head[1]);
  if (head[0] != static_cast<uint8_t>(Opcode::HEADER)) {
    addDamage(kMagicSize, "byte 8: a " + opcodeName(head[0]) + " where the Header should be");
  } else if (length > size_ - kMagicSize - kRecordHeaderSize) {
    addDamage(size_, "truncated at byte " + str(size_) + " inside the Header record (declares " +
                         str(length) + " bytes)");
    return;
  } else {
    const std::vector<uint8_t> content = readAt(kMagicSize + kRecordHeaderSize, length);
    try {
      header_ = parseHeader(content.data(), content.size());
    } catch (const ParseError& e) {
      addDamage(kMagicSize, std::string("Header record at byte 8: ") + e.what());
    }
    data_start = kMagicSize + kRecordHeaderSize + length;
  }
  indexed_ = readSummary();
  if (!indexed_) scan(data_start);
}

// ---- the summary

bool McapReader::readSummary() {
  constexpr uint64_t kTail = kFooterRecordSize + kMagicSize;
  const char* kLinear = "; read by a linear scan";
  const uint64_t footer_offset = size_ >= kMagicSize + kTail ? size_ - kTail : 0;
  const std::vector<uint8_t> tail =
      footer_offset > 0 ? readAt(footer_offset, kTail) : std::vector<uint8_t>();
  if (tail.empty() || std::memcmp(tail.data() + kFooterRecordSize, kMagic, kMagicSize) != 0 ||
      tail[0] != static_cast<uint8_t>(Opcode::FOOTER) || readU64(&tail[1]) != kFooterContentSize) {
    addDamage(size_, "no footer at the end of the file (byte " + str(size_) +
                         "): cut short, or not closed" + kLinear);
    return false;
  }
  const Footer footer = parseFooter(tail.data() + kRecordHeaderSize, kFooterContentSize);
  if (footer.summary_start == 0) return false;  // written without a summary: read in order
  const std::string at_footer = "footer at byte " + str(footer_offset) + ": ";
  if (footer.summary_start < kMagicSize || footer.summary_start > footer_offset ||
      (footer.summary_offset_start != 0 && (footer.summary_offset_start < footer.summary_start ||
                                            footer.summary_offset_start > footer_offset))) {
    addDamage(footer_offset, at_footer + "summary offsets " + str(footer.summary_start) + ", " +
                                 str(footer.summary_offset_start) + " are outside the file" +
                                 kLinear);
    return false;
  }
  const uint64_t summary_size = footer_offset - footer.summary_start;
  if (summary_size > kMaxChunkBytes) {
    addDamage(footer_offset, at_footer + "a summary of " + str(summary_size) + " bytes" + kLinear);
    return false;
  }
  const std::vector<uint8_t> summary = readAt(footer.summary_start, summary_size);
  const std::string at_summary = "summary at byte " + str(footer.summary_start) + ": ";
  if (footer.summary_crc != 0) {
    uint32_t crc = crc32Update(0, summary.data(), summary.size());
    crc = crc32Update(crc, tail.data(), kRecordHeaderSize + 16);
    if (crc != footer.summary_crc) {
      addDamage(footer.summary_start, at_summary + "CRC mismatch (computed " + hex32(crc) +
                                          ", the footer says " + hex32(footer.summary_crc) + ")" +
                                          kLinear);
      return false;
    }
  }
  const uint64_t records_end = footer.summary_offset_start != 0
                                   ? footer.summary_offset_start - footer.summary_start
                                   : summary_size;
  bool have_statistics = false;
  std::vector<MetadataIndex> metadata_indexes;
  try {
    forEachRecord(summary.data(), records_end,
                  [&](uint8_t op, const uint8_t* content, uint64_t length, uint64_t) {
                    switch (static_cast<Opcode>(op)) {
                      case Opcode::SCHEMA:
                        registerSchema(parseSchema(content, length));
                        break;
                      case Opcode::CHANNEL:
                        registerChannel(parseChannel(content, length));
                        break;
                      case Opcode::CHUNK_INDEX:
                        chunks_.push_back(parseChunkIndex(content, length));
                        break;
                      case Opcode::STATISTICS:
                        statistics_ = parseStatistics(content, length);
                        have_statistics = true;
                        break;
                      case Opcode::METADATA_INDEX:
                        metadata_indexes.push_back(parseMetadataIndex(content, length));
                        break;
                      case Opcode::ATTACHMENT_INDEX:
                        ++attachment_count_;
                        break;
                      default:
                        break;  // others (and future records) are not needed here
                    }
                  });
  } catch (const ParseError& e) {
    addDamage(footer.summary_start, at_summary + e.what() + kLinear);
    return false;
  }
  if (footer.summary_start >= kMagicSize + kDataEndRecordSize) {
    const uint64_t at = footer.summary_start - kDataEndRecordSize;
    const std::vector<uint8_t> data_end = readAt(at, kDataEndRecordSize);
    if (data_end[0] == static_cast<uint8_t>(Opcode::DATA_END) && readU64(&data_end[1]) == 4) {
      data_end_ = at;
      data_crc_ = readU32(&data_end[kRecordHeaderSize]);
    }
  }
  std::sort(chunks_.begin(), chunks_.end(), [](const ChunkIndex& a, const ChunkIndex& b) {
    return a.chunk_start_offset < b.chunk_start_offset;
  });
  if (!checkSummaryIndexes(footer.summary_start)) return false;
  // Messages outside chunks have no index: such a file is read in order (the scan finds its
  // Metadata records itself).
  if (chunks_.empty() && (!have_statistics || statistics_.message_count > 0)) return false;
  chunk_states_.assign(chunks_.size(), ChunkState::UNCHECKED);
  for (const MetadataIndex& index : metadata_indexes) {
    if (index.length < kRecordHeaderSize || index.offset < kMagicSize ||
        index.offset > footer.summary_start || index.length > footer.summary_start - index.offset ||
        index.length > kMaxChunkBytes) {
      addDamage(index.offset,
                "Metadata Index '" + index.name + "' points outside the data section");
      continue;
    }
    const std::vector<uint8_t> record = readAt(index.offset, index.length);
    try {
      if (record[0] != static_cast<uint8_t>(Opcode::METADATA) ||
          readU64(&record[1]) != record.size() - kRecordHeaderSize) {
        throw ParseError("no Metadata record there");
      }
      metadata_.push_back(
          parseMetadata(record.data() + kRecordHeaderSize, record.size() - kRecordHeaderSize));
    } catch (const ParseError& e) {
      addDamage(index.offset,
                "metadata '" + index.name + "' at byte " + str(index.offset) + ": " + e.what());
    }
  }
  if (!have_statistics) statisticsFromMessageIndexes();
  return true;
}

bool McapReader::checkSummaryIndexes(uint64_t summary_start) {
  const uint64_t data_end = data_end_ ? *data_end_ : summary_start;
  for (const ChunkIndex& index : chunks_) {
    const uint64_t at = index.chunk_start_offset;
    if (at < kMagicSize || at > data_end || index.chunk_length < kRecordHeaderSize ||
        index.chunk_length > data_end - at) {
      addDamage(at, "summary: the Chunk Index of a chunk at byte " + str(at) + " (" +
                        str(index.chunk_length) +
                        " bytes) points outside the data section; read by a linear scan");
      schemas_.clear();
      channels_.clear();
      chunks_.clear();
      return false;
    }
  }
  return true;
}

void McapReader::statisticsFromMessageIndexes() {
  // A summary without Statistics: counts from the Message Index records after each chunk.
  Statistics& s = statistics_;
  s = Statistics{};
  bool any = false;
  for (const ChunkIndex& index : chunks_) {
    const uint64_t at = index.chunk_start_offset + index.chunk_length;
    if (index.message_index_length > kMaxChunkBytes || at > size_ ||
        index.message_index_length > size_ - at) {
      addDamage(at, "the Message Index records after the chunk at byte " +
                        str(index.chunk_start_offset) + " run past the end of the file");
      continue;
    }
    const std::vector<uint8_t> bytes = readAt(at, index.message_index_length);
    try {
      forEachRecord(bytes.data(), bytes.size(),
                    [&](uint8_t op, const uint8_t* content, uint64_t length, uint64_t) {
                      if (op != static_cast<uint8_t>(Opcode::MESSAGE_INDEX)) return;
                      const MessageIndex message_index = parseMessageIndex(content, length);
                      s.channel_message_counts[message_index.channel_id] +=
                          message_index.entries.size();
                      s.message_count += message_index.entries.size();
                    });
    } catch (const ParseError& e) {
      addDamage(at, "Message Index records at byte " + str(at) + ": " + e.what());
    }
    if (index.message_index_offsets.empty()) continue;  // a chunk without messages
    s.message_start_time =
        any ? std::min(s.message_start_time, index.message_start_time) : index.message_start_time;
    s.message_end_time =
        any ? std::max(s.message_end_time, index.message_end_time) : index.message_end_time;
    any = true;
  }
  s.schema_count = static_cast<uint16_t>(schemas_.size());
  s.channel_count = static_cast<uint32_t>(channels_.size());
  s.chunk_count = static_cast<uint32_t>(chunks_.size());
  s.metadata_count = static_cast<uint32_t>(metadata_.size());
  s.attachment_count = attachment_count_;
}

void McapReader::registerSchema(Schema schema) {
  if (schema.id == 0) return;                      // invalid by the spec: ignored
  schemas_.emplace(schema.id, std::move(schema));  // the first one wins; duplicates are equal
}

void McapReader::registerChannel(Channel channel) {
  channels_.emplace(channel.id, std::move(channel));
}

// ---- chunks

std::optional<McapReader::LoadedChunk> McapReader::loadChunk(size_t chunk,
                                                             const std::vector<uint8_t>* given) {
  if (chunk_states_[chunk] == ChunkState::DAMAGED) return std::nullopt;
  const ChunkIndex& index = chunks_[chunk];
  const uint64_t at = index.chunk_start_offset;
  auto fail = [&](const std::string& why) -> std::optional<LoadedChunk> {
    chunk_states_[chunk] = ChunkState::DAMAGED;
    addDamage(at, "chunk at byte " + str(at) + ": " + why);
    return std::nullopt;
  };
  std::vector<uint8_t> own;
  if (!given) {
    if (index.chunk_length > kMaxChunkBytes) {
      return fail(str(index.chunk_length) + " bytes, more than a chunk may have");
    }
    own = readAt(at, index.chunk_length);
    given = &own;
  }
  const std::vector<uint8_t>& bytes = *given;
  if (bytes.size() < kRecordHeaderSize || bytes[0] != static_cast<uint8_t>(Opcode::CHUNK) ||
      readU64(&bytes[1]) != bytes.size() - kRecordHeaderSize) {
    return fail("no Chunk record of " + str(bytes.size()) + " bytes there (a " +
                opcodeName(bytes.empty() ? 0 : bytes[0]) + ")");
  }
  const uint8_t* content = bytes.data() + kRecordHeaderSize;
  ChunkHeader header;
  try {
    header = parseChunkHeader(content, bytes.size() - kRecordHeaderSize);
  } catch (const ParseError& e) {
    return fail(e.what());
  }
  if (indexed_) {
    const std::string differs = disagreement(header, index);
    if (!differs.empty()) return fail("its header disagrees with its Chunk Index: " + differs);
  }
  if (header.uncompressed_size > kMaxChunkBytes) {
    return fail("declares " + str(header.uncompressed_size) +
                " uncompressed bytes, more than a chunk may have");
  }
  std::vector<uint8_t> records;
  try {
    records = decompress(header.compression, content + header.records_offset, header.records_size,
                         header.uncompressed_size);
  } catch (const std::runtime_error& e) {
    return fail(e.what());
  }
  if (header.uncompressed_crc != 0) {
    const uint32_t crc = crc32Update(0, records.data(), records.size());
    if (crc != header.uncompressed_crc) {
      return fail("CRC mismatch (its records give " + hex32(crc) + ", the chunk says " +
                  hex32(header.uncompressed_crc) + ")");
    }
  }
  LoadedChunk loaded;
  std::vector<Schema> schemas;
  std::vector<Channel> channels;
  try {
    forEachRecord(
        records.data(), records.size(),
        [&](uint8_t op, const uint8_t* record, uint64_t length, uint64_t offset) {
          if (op == static_cast<uint8_t>(Opcode::MESSAGE)) {
            const Message message = parseMessage(record, length, false);
            if (message.log_time < header.message_start_time ||
                message.log_time > header.message_end_time) {
              throw ParseError("log time " + str(message.log_time) + " outside the chunk's [" +
                               str(header.message_start_time) + ", " +
                               str(header.message_end_time) + "]");
            }
            loaded.entries.push_back(MessageIterator::Entry{
                message.log_time, offset + kRecordHeaderSize, length, message.channel_id});
          } else if (op == static_cast<uint8_t>(Opcode::SCHEMA)) {
            schemas.push_back(parseSchema(record, length));
          } else if (op == static_cast<uint8_t>(Opcode::CHANNEL)) {
            channels.push_back(parseChannel(record, length));
          }
        });
  } catch (const ParseError& e) {
    return fail(std::string("in its records: ") + e.what());
  }
  for (Schema& schema : schemas) registerSchema(std::move(schema));
  for (Channel& channel : channels) registerChannel(std::move(channel));
  std::map<uint16_t, uint64_t> unknown;
  auto undefined = [&](const MessageIterator::Entry& entry) {
    if (channels_.count(entry.channel_id)) return false;
    ++unknown[entry.channel_id];
    return true;
  };
  loaded.entries.erase(std::remove_if(loaded.entries.begin(), loaded.entries.end(), undefined),
                       loaded.entries.end());
  if (chunk_states_[chunk] == ChunkState::UNCHECKED) {
    for (const auto& [channel, count] : unknown) {
      addDamage(at, "chunk at byte " + str(at) + ": " + str(count) + " messages on channel " +
                        str(channel) + ", which no Channel record defines, skipped");
    }
  }
  chunk_states_[chunk] = ChunkState::INTACT;
  loaded.records = std::make_shared<const std::vector<uint8_t>>(std::move(records));
  return loaded;
}

bool McapReader::verify() {
  for (size_t i = 0; i < chunks_.size(); ++i) {
    if (chunk_states_[i] == ChunkState::UNCHECKED) loadChunk(i);
  }
  if (data_end_ && data_crc_ != 0 && !data_crc_checked_) {
    data_crc_checked_ = true;
    const uint32_t crc = crcOfRange(0, 0, *data_end_);
    if (crc != data_crc_) {
      addDamage(0, "data section CRC mismatch (bytes 0 to " + str(*data_end_) + " give " +
                       hex32(crc) + ", the Data End record says " + hex32(data_crc_) + ")");
    }
  }
  return damage_.empty();
}

MessageIterator McapReader::messages(const ReadFilter& filter) {
  if (fd_ < 0) throw std::logic_error("McapReader::messages: no file open");
  return MessageIterator(*this, filter);
}

std::vector<BagMessage> McapReader::readMessages(const ReadFilter& filter) {
  std::vector<BagMessage> all;
  MessageIterator iterator = messages(filter);
  while (auto message = iterator.next()) all.push_back(std::move(*message));
  return all;
}

}  // namespace auv::bag
