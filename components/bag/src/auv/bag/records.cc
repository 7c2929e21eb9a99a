#include "auv/bag/records.h"

#include <cstring>
#include <sstream>

namespace auv::bag {

std::string opcodeName(uint8_t opcode) {
  switch (static_cast<Opcode>(opcode)) {
    case Opcode::HEADER:
      return "Header";
    case Opcode::FOOTER:
      return "Footer";
    case Opcode::SCHEMA:
      return "Schema";
    case Opcode::CHANNEL:
      return "Channel";
    case Opcode::MESSAGE:
      return "Message";
    case Opcode::CHUNK:
      return "Chunk";
    case Opcode::MESSAGE_INDEX:
      return "Message Index";
    case Opcode::CHUNK_INDEX:
      return "Chunk Index";
    case Opcode::ATTACHMENT:
      return "Attachment";
    case Opcode::ATTACHMENT_INDEX:
      return "Attachment Index";
    case Opcode::STATISTICS:
      return "Statistics";
    case Opcode::METADATA:
      return "Metadata";
    case Opcode::METADATA_INDEX:
      return "Metadata Index";
    case Opcode::SUMMARY_OFFSET:
      return "Summary Offset";
    case Opcode::DATA_END:
      return "Data End";
  }
  std::ostringstream text;
  text << "record of opcode 0x" << std::hex << static_cast<int>(opcode);
  return text.str();
}

// ---- serialization

namespace {

/// Stores `v` little endian at `p`, whatever the host's byte order.
template <class T>
void store(uint8_t* p, T v) {
  for (size_t i = 0; i < sizeof(T); ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}

}  // namespace

// Fields are stored into resized memory rather than pushed byte by byte: the writer spends
// its time here for small messages.
void RecordBuffer::u16(uint16_t v) {
  bytes_.resize(bytes_.size() + 2);
  store(bytes_.data() + bytes_.size() - 2, v);
}
void RecordBuffer::u32(uint32_t v) {
  bytes_.resize(bytes_.size() + 4);
  store(bytes_.data() + bytes_.size() - 4, v);
}
void RecordBuffer::u64(uint64_t v) {
  bytes_.resize(bytes_.size() + 8);
  store(bytes_.data() + bytes_.size() - 8, v);
}
void RecordBuffer::string(const std::string& s) {
  u32(static_cast<uint32_t>(s.size()));
  bytes_.insert(bytes_.end(), s.begin(), s.end());
}
void RecordBuffer::stringMap(const StringMap& map) {
  const size_t at = bytes_.size();
  u32(0);
  for (const auto& [key, value] : map) {
    string(key);
    string(value);
  }
  const auto length = static_cast<uint32_t>(bytes_.size() - at - 4);
  for (int i = 0; i < 4; ++i) bytes_[at + i] = static_cast<uint8_t>(length >> (8 * i));
}

size_t RecordBuffer::begin(Opcode opcode) {
  const size_t start = bytes_.size();
  u8(static_cast<uint8_t>(opcode));
  u64(0);
  return start;
}

void RecordBuffer::end(size_t start) {
  const uint64_t length = bytes_.size() - start - kRecordHeaderSize;
  for (int i = 0; i < 8; ++i) bytes_[start + 1 + i] = static_cast<uint8_t>(length >> (8 * i));
}

void RecordBuffer::header(const Header& header) {
  const size_t start = begin(Opcode::HEADER);
  string(header.profile);
  string(header.library);
  end(start);
}

void RecordBuffer::footer(const Footer& footer) {
  const size_t start = begin(Opcode::FOOTER);
  u64(footer.summary_start);
  u64(footer.summary_offset_start);
  u32(footer.summary_crc);
  end(start);
}

void RecordBuffer::schema(const Schema& schema) {
  const size_t start = begin(Opcode::SCHEMA);
  u16(schema.id);
  string(schema.name);
  string(schema.encoding);
  string(schema.data);  // uint32 length-prefixed bytes, like a string
  end(start);
}

void RecordBuffer::channel(const Channel& channel) {
  const size_t start = begin(Opcode::CHANNEL);
  u16(channel.id);
  u16(channel.schema_id);
  string(channel.topic);
  string(channel.message_encoding);
  stringMap(channel.metadata);
  end(start);
}

void RecordBuffer::message(uint16_t channel_id, uint32_t sequence, uint64_t log_time,
                           uint64_t publish_time, const uint8_t* data, size_t size) {
  const size_t at = bytes_.size();
  bytes_.resize(at + kRecordHeaderSize + kMessageFixedSize + size);
  uint8_t* p = bytes_.data() + at;
  p[0] = static_cast<uint8_t>(Opcode::MESSAGE);
  store<uint64_t>(p + 1, kMessageFixedSize + size);
  store(p + 9, channel_id);
  store(p + 11, sequence);
  store(p + 15, log_time);
  store(p + 23, publish_time);
  if (size > 0) std::memcpy(p + kRecordHeaderSize + kMessageFixedSize, data, size);
}

void RecordBuffer::chunkPrefix(const ChunkHeader& chunk) {
  u8(static_cast<uint8_t>(Opcode::CHUNK));
  u64(8 + 8 + 8 + 4 + 4 + chunk.compression.size() + 8 + chunk.records_size);
  u64(chunk.message_start_time);
  u64(chunk.message_end_time);
  u64(chunk.uncompressed_size);
  u32(chunk.uncompressed_crc);
  string(chunk.compression);
  u64(chunk.records_size);
}

void RecordBuffer::messageIndex(const MessageIndex& index) {
  const size_t start = begin(Opcode::MESSAGE_INDEX);
  u16(index.channel_id);
  u32(static_cast<uint32_t>(index.entries.size() * 16));
  for (const auto& [time, offset] : index.entries) {
    u64(time);
    u64(offset);
  }
  end(start);
}

void RecordBuffer::chunkIndex(const ChunkIndex& index) {
  const size_t start = begin(Opcode::CHUNK_INDEX);
  u64(index.message_start_time);
  u64(index.message_end_time);
  u64(index.chunk_start_offset);
  u64(index.chunk_length);
  u32(static_cast<uint32_t>(index.message_index_offsets.size() * 10));
  for (const auto& [channel, offset] : index.message_index_offsets) {
    u16(channel);
    u64(offset);
  }
  u64(index.message_index_length);
  string(index.compression);
  u64(index.compressed_size);
  u64(index.uncompressed_size);
  end(start);
}

void RecordBuffer::statistics(const Statistics& s) {
  const size_t start = begin(Opcode::STATISTICS);
  u64(s.message_count);
  u16(s.schema_count);
  u32(s.channel_count);
  u32(s.attachment_count);
  u32(s.metadata_count);
  u32(s.chunk_count);
  u64(s.message_start_time);
  u64(s.message_end_time);
  u32(static_cast<uint32_t>(s.channel_message_counts.size() * 10));
  for (const auto& [channel, count] : s.channel_message_counts) {
    u16(channel);
    u64(count);
  }
  end(start);
}

void RecordBuffer::metadata(const Metadata& metadata) {
  const size_t start = begin(Opcode::METADATA);
  string(metadata.name);
  stringMap(metadata.metadata);
  end(start);
}

void RecordBuffer::metadataIndex(const MetadataIndex& index) {
  const size_t start = begin(Opcode::METADATA_INDEX);
  u64(index.offset);
  u64(index.length);
  string(index.name);
  end(start);
}

void RecordBuffer::summaryOffset(const SummaryOffset& offset) {
  const size_t start = begin(Opcode::SUMMARY_OFFSET);
  u8(offset.group_opcode);
  u64(offset.group_start);
  u64(offset.group_length);
  end(start);
}

void RecordBuffer::dataEnd(uint32_t data_section_crc) {
  const size_t start = begin(Opcode::DATA_END);
  u32(data_section_crc);
  end(start);
}

// ---- parsing

uint16_t readU16(const uint8_t* p) { return static_cast<uint16_t>(p[0] | (p[1] << 8)); }
uint32_t readU32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) |
         (static_cast<uint32_t>(p[2]) << 16) | (static_cast<uint32_t>(p[3]) << 24);
}
uint64_t readU64(const uint8_t* p) {
  return static_cast<uint64_t>(readU32(p)) | (static_cast<uint64_t>(readU32(p + 4)) << 32);
}

void ByteReader::need(uint64_t count, const char* field) const {
  if (count > size_ - offset_) {
    std::ostringstream text;
    text << field << " needs " << count << " bytes at record offset " << offset_ << ", "
         << (size_ - offset_) << " left";
    throw ParseError(text.str());
  }
}

uint8_t ByteReader::u8(const char* field) {
  need(1, field);
  return data_[offset_++];
}
uint16_t ByteReader::u16(const char* field) {
  need(2, field);
  offset_ += 2;
  return readU16(data_ + offset_ - 2);
}
uint32_t ByteReader::u32(const char* field) {
  need(4, field);
  offset_ += 4;
  return readU32(data_ + offset_ - 4);
}
uint64_t ByteReader::u64(const char* field) {
  need(8, field);
  offset_ += 8;
  return readU64(data_ + offset_ - 8);
}
const uint8_t* ByteReader::bytes(uint64_t count, const char* field) {
  need(count, field);
  const uint8_t* at = data_ + offset_;
  offset_ += static_cast<size_t>(count);
  return at;
}
std::string ByteReader::string(const char* field) {
  const uint32_t length = u32(field);
  const uint8_t* at = bytes(length, field);
  return std::string(reinterpret_cast<const char*>(at), length);
}
StringMap ByteReader::stringMap(const char* field) {
  const uint32_t length = u32(field);
  ByteReader inner(bytes(length, field), length);
  StringMap map;
  while (inner.remaining() > 0) {
    std::string key = inner.string(field);
    map[key] = inner.string(field);
  }
  return map;
}

Header parseHeader(const uint8_t* data, size_t size) {
  ByteReader in(data, size);
  Header header;
  header.profile = in.string("Header.profile");
  header.library = in.string("Header.library");
  return header;
}

Footer parseFooter(const uint8_t* data, size_t size) {
  ByteReader in(data, size);
  Footer footer;
  footer.summary_start = in.u64("Footer.summary_start");
  footer.summary_offset_start = in.u64("Footer.summary_offset_start");
  footer.summary_crc = in.u32("Footer.summary_crc");
  return footer;
}

Schema parseSchema(const uint8_t* data, size_t size) {
  ByteReader in(data, size);
  Schema schema;
  schema.id = in.u16("Schema.id");
  schema.name = in.string("Schema.name");
  schema.encoding = in.string("Schema.encoding");
  schema.data = in.string("Schema.data");
  return schema;
}

Channel parseChannel(const uint8_t* data, size_t size) {
  ByteReader in(data, size);
  Channel channel;
  channel.id = in.u16("Channel.id");
  channel.schema_id = in.u16("Channel.schema_id");
  channel.topic = in.string("Channel.topic");
  channel.message_encoding = in.string("Channel.message_encoding");
  channel.metadata = in.stringMap("Channel.metadata");
  return channel;
}

Message parseMessage(const uint8_t* data, size_t size, bool with_data) {
  ByteReader in(data, size);
  Message message;
  message.channel_id = in.u16("Message.channel_id");
  message.sequence = in.u32("Message.sequence");
  message.log_time = in.u64("Message.log_time");
  message.publish_time = in.u64("Message.publish_time");
  if (with_data) message.data.assign(data + in.offset(), data + size);
  return message;
}

ChunkHeader parseChunkHeader(const uint8_t* data, size_t size) {
  ByteReader in(data, size);
  ChunkHeader chunk;
  chunk.message_start_time = in.u64("Chunk.message_start_time");
  chunk.message_end_time = in.u64("Chunk.message_end_time");
  chunk.uncompressed_size = in.u64("Chunk.uncompressed_size");
  chunk.uncompressed_crc = in.u32("Chunk.uncompressed_crc");
  chunk.compression = in.string("Chunk.compression");
  chunk.records_size = in.u64("Chunk.records");
  chunk.records_offset = in.offset();
  in.bytes(chunk.records_size, "Chunk.records");
  return chunk;
}

MessageIndex parseMessageIndex(const uint8_t* data, size_t size) {
  ByteReader in(data, size);
  MessageIndex index;
  index.channel_id = in.u16("MessageIndex.channel_id");
  const uint32_t length = in.u32("MessageIndex.records");
  if (length % 16 != 0) throw ParseError("MessageIndex.records: length not a multiple of 16");
  ByteReader entries(in.bytes(length, "MessageIndex.records"), length);
  index.entries.reserve(length / 16);
  while (entries.remaining() > 0) {
    const uint64_t time = entries.u64("MessageIndex.log_time");
    index.entries.emplace_back(time, entries.u64("MessageIndex.offset"));
  }
  return index;
}

ChunkIndex parseChunkIndex(const uint8_t* data, size_t size) {
  ByteReader in(data, size);
  ChunkIndex index;
  index.message_start_time = in.u64("ChunkIndex.message_start_time");
  index.message_end_time = in.u64("ChunkIndex.message_end_time");
  index.chunk_start_offset = in.u64("ChunkIndex.chunk_start_offset");
  index.chunk_length = in.u64("ChunkIndex.chunk_length");
  const uint32_t length = in.u32("ChunkIndex.message_index_offsets");
  ByteReader offsets(in.bytes(length, "ChunkIndex.message_index_offsets"), length);
  while (offsets.remaining() > 0) {
    const uint16_t channel = offsets.u16("ChunkIndex.message_index_offsets");
    index.message_index_offsets[channel] = offsets.u64("ChunkIndex.message_index_offsets");
  }
  index.message_index_length = in.u64("ChunkIndex.message_index_length");
  index.compression = in.string("ChunkIndex.compression");
  index.compressed_size = in.u64("ChunkIndex.compressed_size");
  index.uncompressed_size = in.u64("ChunkIndex.uncompressed_size");
  return index;
}

Statistics parseStatistics(const uint8_t* data, size_t size) {
  ByteReader in(data, size);
  Statistics s;
  s.message_count = in.u64("Statistics.message_count");
  s.schema_count = in.u16("Statistics.schema_count");
  s.channel_count = in.u32("Statistics.channel_count");
  s.attachment_count = in.u32("Statistics.attachment_count");
  s.metadata_count = in.u32("Statistics.metadata_count");
  s.chunk_count = in.u32("Statistics.chunk_count");
  s.message_start_time = in.u64("Statistics.message_start_time");
  s.message_end_time = in.u64("Statistics.message_end_time");
  const uint32_t length = in.u32("Statistics.channel_message_counts");
  ByteReader counts(in.bytes(length, "Statistics.channel_message_counts"), length);
  while (counts.remaining() > 0) {
    const uint16_t channel = counts.u16("Statistics.channel_message_counts");
    s.channel_message_counts[channel] = counts.u64("Statistics.channel_message_counts");
  }
  return s;
}

Metadata parseMetadata(const uint8_t* data, size_t size) {
  ByteReader in(data, size);
  Metadata metadata;
  metadata.name = in.string("Metadata.name");
  metadata.metadata = in.stringMap("Metadata.metadata");
  return metadata;
}

MetadataIndex parseMetadataIndex(const uint8_t* data, size_t size) {
  ByteReader in(data, size);
  MetadataIndex index;
  index.offset = in.u64("MetadataIndex.offset");
  index.length = in.u64("MetadataIndex.length");
  index.name = in.string("MetadataIndex.name");
  return index;
}

SummaryOffset parseSummaryOffset(const uint8_t* data, size_t size) {
  ByteReader in(data, size);
  SummaryOffset offset;
  offset.group_opcode = in.u8("SummaryOffset.group_opcode");
  offset.group_start = in.u64("SummaryOffset.group_start");
  offset.group_length = in.u64("SummaryOffset.group_length");
  return offset;
}

uint32_t parseDataEnd(const uint8_t* data, size_t size) {
  ByteReader in(data, size);
  return in.u32("DataEnd.data_section_crc");
}

}  // namespace auv::bag
