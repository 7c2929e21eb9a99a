#pragma once
// Writes MCAP files (mcap.dev/spec) for `auv bag record`: schemas (OMG IDL text) and
// channels (topic, encoding "cdr", QoS in the metadata) as they are discovered, then
// messages in compressed chunks, each followed by its Message Index records; close() adds the
// summary (schemas, channels, statistics, chunk and metadata indexes, summary offsets) and the
// footer. The file is written as `<path>.part` and renamed at close(): every chunk is written
// out whole before the next one starts, so a writer that dies leaves a `.part` file whose
// complete chunks McapReader recovers. Layout and recovery: components/bag/README.md.

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "auv/bag/records.h"
#include "auv/config/option_table.h"

namespace auv::bag {

class Compressor;

struct McapWriterOptions {
  std::string profile;                      ///< the Header's profile: "" or e.g. "ros2"
  std::string library = "auv-inspect";      ///< the Header's library
  std::string compression = "zstd";         ///< chunk compression: none, zstd or lz4
  int compression_level = 0;                ///< 0: default (zstd 1, lz4 fast); zstd 1-19, lz4 1-12
  uint64_t chunk_size = uint64_t{1} << 20;  ///< bytes of records after which a chunk is written
  bool overwrite = false;                   ///< replace an existing file (else refuse)
  bool fsync_chunks = false;                ///< fsync after each chunk (survives power loss)

  static const config::OptionTable<McapWriterOptions>& table();
  /// Throws std::invalid_argument naming the field and the value.
  void check() const;
};

/// What a writer has written so far.
struct WriterStats {
  uint64_t messages = 0;
  uint64_t chunks = 0;              ///< chunks written out
  uint64_t uncompressed_bytes = 0;  ///< records in those chunks, before compression
  uint64_t file_bytes = 0;          ///< bytes in the file
};

/// Not thread-safe: a recorder calls it from one thread, or under one lock.
class McapWriter {
 public:
  /// Checks the options (std::invalid_argument).
  explicit McapWriter(McapWriterOptions options = {});
  /// Closes an open file (errors are swallowed: call close() to see them).
  ~McapWriter();
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  /// Starts `path` (as `<path>.part`): magic and Header. Throws BagError EXISTS if `path` or
  /// `<path>.part` exists and overwrite is off, IO if the file cannot be created.
  void open(const std::filesystem::path& path);
  bool isOpen() const { return fd_ >= 0; }
  const std::filesystem::path& path() const { return path_; }

  /// The id of a schema (1, 2, ...); the same schema given again gets its first id.
  uint16_t addSchema(const std::string& name, const std::string& encoding, const std::string& data);
  /// The id of a channel (1, 2, ...) of `schema_id` (0: none); the same channel again gets
  /// its first id. Throws std::invalid_argument for a schema id never added.
  uint16_t addChannel(uint16_t schema_id, const std::string& topic,
                      const std::string& message_encoding, const StringMap& metadata = {});
  /// Adds a message to the current chunk, writing the chunk out once it holds chunk_size
  /// bytes. Throws std::invalid_argument for an unknown channel or a message over
  /// kMaxMessageBytes, BagError IO when the file cannot be written.
  void write(uint16_t channel_id, uint32_t sequence, uint64_t log_time_ns, uint64_t publish_time_ns,
             const uint8_t* data, size_t size);
  void write(uint16_t channel_id, uint32_t sequence, uint64_t log_time_ns, uint64_t publish_time_ns,
             const std::vector<uint8_t>& data) {
    write(channel_id, sequence, log_time_ns, publish_time_ns, data.data(), data.size());
  }
  /// A Metadata record (e.g. the recording's vehicle, mission, software version).
  void addMetadata(const std::string& name, const StringMap& metadata);
  /// Writes the current chunk out now (a recorder calls it on a timer, so a crash loses at
  /// most that period of a slow topic).
  void flush();
  /// Last chunk, Data End, summary, footer; fsync and rename to the final path. Throws
  /// BagError IO (the `.part` file is kept) or EXISTS if the path appeared meanwhile.
  void close();

  WriterStats stats() const { return stats_; }
  const McapWriterOptions& options() const { return options_; }

 private:
  void requireOpen(const char* what) const;
  /// Writes `size` bytes; `crc`, when given, is theirs (the data CRC needs no pass over them).
  void writeBytes(const uint8_t* data, size_t size, const uint32_t* crc = nullptr);
  /// `whole`: the buffer ends with a whole record (a failed write later truncates to here).
  void writeRecords(const RecordBuffer& records, bool whole = true);
  void writeChunk();
  void writeSummary();
  void closeFile() noexcept;

  McapWriterOptions options_;
  std::filesystem::path path_;       // final
  std::filesystem::path part_path_;  // being written
  int fd_ = -1;
  uint64_t offset_ = 0;     // bytes written so far
  uint64_t whole_end_ = 0;  // end of the last whole record written
  uint32_t data_crc_ = 0;   // of every byte up to the Data End record

  std::vector<Schema> schemas_;    // by id - 1
  std::vector<Channel> channels_;  // by id - 1
  std::vector<Metadata> metadata_;
  std::vector<MetadataIndex> metadata_indexes_;
  std::vector<ChunkIndex> chunk_indexes_;
  Statistics statistics_;

  // The chunk being filled: Message records, their index per channel, time bounds.
  RecordBuffer chunk_;
  std::map<uint16_t, MessageIndex> chunk_index_;
  uint64_t chunk_start_ = 0;
  uint64_t chunk_end_ = 0;
  std::vector<uint8_t> compressed_;
  std::unique_ptr<Compressor> compressor_;

  WriterStats stats_;
};

}  // namespace auv::bag
