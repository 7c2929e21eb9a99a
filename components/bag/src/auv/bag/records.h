#pragma once
// MCAP records (format version 0, mcap.dev/spec): their fields, their serialization (little
// endian; strings, maps and arrays prefixed by a uint32 byte length) and parsing that checks
// every length against the bytes it has, so no input can read out of bounds.

#include <cstddef>
#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace auv::bag {

/// The 8 bytes an MCAP file begins and ends with: 0x89 "MCAP" '0' (major version) "\r\n".
inline constexpr uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
inline constexpr size_t kMagicSize = 8;
/// opcode (1 byte) + content length (uint64)
inline constexpr size_t kRecordHeaderSize = 9;
/// A Footer record: summary_start, summary_offset_start (uint64), summary_crc (uint32).
inline constexpr size_t kFooterContentSize = 20;
inline constexpr size_t kFooterRecordSize = kRecordHeaderSize + kFooterContentSize;
/// A DataEnd record: data_section_crc (uint32).
inline constexpr size_t kDataEndRecordSize = kRecordHeaderSize + 4;
/// Message record content before the data: channel_id, sequence, log_time, publish_time.
inline constexpr size_t kMessageFixedSize = 2 + 4 + 8 + 8;
/// The largest chunk (uncompressed records) or summary we read: a larger size field is taken
/// for damage rather than allocated. The writer keeps its chunks well below it.
inline constexpr uint64_t kMaxChunkBytes = uint64_t{2} << 30;
/// The largest message the writer accepts (its chunk stays under kMaxChunkBytes).
inline constexpr uint64_t kMaxMessageBytes = uint64_t{1} << 30;

enum class Opcode : uint8_t {
  HEADER = 0x01,
  FOOTER = 0x02,
  SCHEMA = 0x03,
  CHANNEL = 0x04,
  MESSAGE = 0x05,
  CHUNK = 0x06,
  MESSAGE_INDEX = 0x07,
  CHUNK_INDEX = 0x08,
  ATTACHMENT = 0x09,
  ATTACHMENT_INDEX = 0x0A,
  STATISTICS = 0x0B,
  METADATA = 0x0C,
  METADATA_INDEX = 0x0D,
  SUMMARY_OFFSET = 0x0E,
  DATA_END = 0x0F,
};

/// "Chunk", "Message Index", ... or "record of opcode 0x42" for one we do not know.
std::string opcodeName(uint8_t opcode);

using StringMap = std::map<std::string, std::string>;

struct Header {
  std::string profile;  ///< "" or a well-known profile such as "ros2"
  std::string library;  ///< the writer, free-form
};

struct Footer {
  uint64_t summary_start = 0;         ///< offset of the summary section, 0: none
  uint64_t summary_offset_start = 0;  ///< offset of the first Summary Offset record, 0: none
  uint32_t summary_crc = 0;           ///< CRC-32 of the summary and footer prefix, 0: none
};

struct Schema {
  uint16_t id = 0;       ///< never 0
  std::string name;      ///< e.g. "auv_msgs::msg::Odometry"
  std::string encoding;  ///< e.g. "omgidl"; "" for no schema
  std::string data;      ///< the schema text (bytes)
  bool operator==(const Schema& o) const {
    return id == o.id && name == o.name && encoding == o.encoding && data == o.data;
  }
};

struct Channel {
  uint16_t id = 0;
  uint16_t schema_id = 0;  ///< 0: no schema
  std::string topic;
  std::string message_encoding;  ///< e.g. "cdr"
  StringMap metadata;            ///< e.g. the QoS the topic was offered with
  bool operator==(const Channel& o) const {
    return id == o.id && schema_id == o.schema_id && topic == o.topic &&
           message_encoding == o.message_encoding && metadata == o.metadata;
  }
};

struct Message {
  uint16_t channel_id = 0;
  uint32_t sequence = 0;
  uint64_t log_time = 0;      ///< ns, when recorded
  uint64_t publish_time = 0;  ///< ns, when published
  std::vector<uint8_t> data;  ///< the serialized message (CDR for us)
};

/// A Chunk record's fields; the records themselves stay in the file.
struct ChunkHeader {
  uint64_t message_start_time = 0;
  uint64_t message_end_time = 0;
  uint64_t uncompressed_size = 0;
  uint32_t uncompressed_crc = 0;  ///< 0: not available
  std::string compression;        ///< "", "zstd" or "lz4"
  uint64_t records_size = 0;      ///< compressed size of the records
  uint64_t records_offset = 0;    ///< where the records begin, from the start of the content
};

struct MessageIndex {
  uint16_t channel_id = 0;
  /// (log_time, offset of the Message record in the uncompressed chunk records)
  std::vector<std::pair<uint64_t, uint64_t>> entries;
};

struct ChunkIndex {
  uint64_t message_start_time = 0;
  uint64_t message_end_time = 0;
  uint64_t chunk_start_offset = 0;  ///< of the Chunk record, from the start of the file
  uint64_t chunk_length = 0;        ///< of the whole Chunk record
  std::map<uint16_t, uint64_t> message_index_offsets;  ///< channel -> Message Index record
  uint64_t message_index_length = 0;  ///< all Message Index records after the chunk
  std::string compression;
  uint64_t compressed_size = 0;
  uint64_t uncompressed_size = 0;
};

struct Statistics {
  uint64_t message_count = 0;
  uint16_t schema_count = 0;
  uint32_t channel_count = 0;
  uint32_t attachment_count = 0;
  uint32_t metadata_count = 0;
  uint32_t chunk_count = 0;
  uint64_t message_start_time = 0;
  uint64_t message_end_time = 0;
  std::map<uint16_t, uint64_t> channel_message_counts;
};

struct Metadata {
  std::string name;
  StringMap metadata;
};

struct MetadataIndex {
  uint64_t offset = 0;  ///< of the Metadata record
  uint64_t length = 0;  ///< of the whole record
  std::string name;
};

struct SummaryOffset {
  uint8_t group_opcode = 0;
  uint64_t group_start = 0;
  uint64_t group_length = 0;
};

/// Appends serialized records to a growing byte buffer (the writer's chunk and summary).
class RecordBuffer {
 public:
  std::vector<uint8_t>& bytes() { return bytes_; }
  const std::vector<uint8_t>& bytes() const { return bytes_; }
  size_t size() const { return bytes_.size(); }
  void clear() { bytes_.clear(); }

  void header(const Header& header);
  void footer(const Footer& footer);
  void schema(const Schema& schema);
  void channel(const Channel& channel);
  /// A Message record carrying `size` bytes of `data`.
  void message(uint16_t channel_id, uint32_t sequence, uint64_t log_time, uint64_t publish_time,
               const uint8_t* data, size_t size);
  /// A Chunk record's opcode, length and fields up to and including the records' length;
  /// the `records_size` compressed bytes follow.
  void chunkPrefix(const ChunkHeader& chunk);
  void messageIndex(const MessageIndex& index);
  void chunkIndex(const ChunkIndex& index);
  void statistics(const Statistics& statistics);
  void metadata(const Metadata& metadata);
  void metadataIndex(const MetadataIndex& index);
  void summaryOffset(const SummaryOffset& offset);
  void dataEnd(uint32_t data_section_crc);

  // Primitives, little endian.
  void u8(uint8_t v) { bytes_.push_back(v); }
  void u16(uint16_t v);
  void u32(uint32_t v);
  void u64(uint64_t v);
  void string(const std::string& s);
  void stringMap(const StringMap& map);

 private:
  /// Starts a record: opcode and a length patched by end(); returns where it starts.
  size_t begin(Opcode opcode);
  void end(size_t start);

  std::vector<uint8_t> bytes_;
};

/// Thrown by ByteReader and the parse functions: a field runs past its record, or a value is
/// impossible. The text names the field.
class ParseError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Reads fields from a record's content, checking each length against what is left.
class ByteReader {
 public:
  ByteReader(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  uint8_t u8(const char* field);
  uint16_t u16(const char* field);
  uint32_t u32(const char* field);
  uint64_t u64(const char* field);
  std::string string(const char* field);
  StringMap stringMap(const char* field);
  /// `count` raw bytes.
  const uint8_t* bytes(uint64_t count, const char* field);
  size_t offset() const { return offset_; }
  size_t remaining() const { return size_ - offset_; }

 private:
  void need(uint64_t count, const char* field) const;

  const uint8_t* data_;
  size_t size_;
  size_t offset_ = 0;
};

uint16_t readU16(const uint8_t* p);
uint32_t readU32(const uint8_t* p);
uint64_t readU64(const uint8_t* p);

// Parse a record's content (the bytes after opcode and length); throw ParseError.
Header parseHeader(const uint8_t* data, size_t size);
Footer parseFooter(const uint8_t* data, size_t size);
Schema parseSchema(const uint8_t* data, size_t size);
Channel parseChannel(const uint8_t* data, size_t size);
/// A Message record; `with_data` false leaves `data` empty (indexing only).
Message parseMessage(const uint8_t* data, size_t size, bool with_data = true);
ChunkHeader parseChunkHeader(const uint8_t* data, size_t size);
MessageIndex parseMessageIndex(const uint8_t* data, size_t size);
ChunkIndex parseChunkIndex(const uint8_t* data, size_t size);
Statistics parseStatistics(const uint8_t* data, size_t size);
Metadata parseMetadata(const uint8_t* data, size_t size);
MetadataIndex parseMetadataIndex(const uint8_t* data, size_t size);
SummaryOffset parseSummaryOffset(const uint8_t* data, size_t size);
uint32_t parseDataEnd(const uint8_t* data, size_t size);

}  // namespace auv::bag
