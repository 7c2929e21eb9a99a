#pragma once
// Reads MCAP files (mcap.dev/spec) for `auv bag play` and `auv bag info`, ours and other
// writers'. A whole file is opened through its footer and summary (schemas, channels,
// statistics, chunk indexes) without touching the data; messages come in log-time order
// across chunks whose times overlap, each chunk's CRC checked as it is read. A truncated or
// damaged file — no footer, a summary that fails its CRC — is read by a linear scan of its
// records instead: every message of every intact chunk is kept, and each break is reported
// as a Damage naming the byte where it is and why ("chunk at byte 123456: CRC mismatch ...",
// "truncated at byte 9000 inside a Chunk record that starts at byte 4096 ..."). Every length
// field is checked against the file, so no input makes it read out of bounds.

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "auv/bag/records.h"

namespace auv::bag {

/// Where a file is damaged and how; reading goes on past it where it can.
struct Damage {
  uint64_t offset = 0;  ///< the byte of the file where it is
  std::string text;     ///< e.g. "chunk at byte 123456: CRC mismatch (...)"
};

/// Which messages to read; times are log times in ns, both ends included.
struct ReadFilter {
  std::vector<std::string> topics;  ///< empty: every topic
  uint64_t start_ns = 0;
  uint64_t end_ns = UINT64_MAX;
};

/// A message of a bag with its channel and schema.
struct BagMessage {
  const Channel* channel = nullptr;  ///< owned by the reader, never null
  const Schema* schema = nullptr;    ///< owned by the reader; null when it has none
  Message message;
  uint64_t chunk_offset = 0;  ///< of the Chunk record it is in; 0 outside chunks
};

class McapReader;

/// Messages of a reader in log-time order (ties in file order), chunks read as they are
/// needed: those whose times overlap are merged, the others read one at a time.
class MessageIterator {
 public:
  /// The next message, or nullopt at the end. Damaged chunks are skipped (and added to the
  /// reader's damage()).
  std::optional<BagMessage> next();

 private:
  friend class McapReader;
  struct Entry {
    uint64_t log_time;
    uint64_t offset;  // of the Message record's content, in `records` or the file
    uint64_t size;
    uint16_t channel_id;
  };
  struct Source {
    uint64_t start_time;
    uint64_t order;  // file offset: breaks ties between sources
    int chunk;       // index into the reader's chunks, -1: the messages outside chunks
  };
  struct Cursor {
    std::shared_ptr<const std::vector<uint8_t>> records;  // null: entries are in the file
    std::vector<Entry> entries;
    size_t next = 0;
    uint64_t order = 0;
    uint64_t chunk_offset = 0;
  };
  MessageIterator(McapReader& reader, ReadFilter filter);
  bool wanted(uint16_t channel_id) const;
  void load(const Source& source);
  bool later(size_t a, size_t b) const;  // heap order of cursors

  McapReader* reader_;
  ReadFilter filter_;
  std::vector<Source> sources_;
  size_t next_source_ = 0;
  std::vector<Cursor> cursors_;
  std::vector<size_t> heap_;  // indices into cursors_
};

class McapReader {
 public:
  McapReader();
  ~McapReader();
  McapReader(const McapReader&) = delete;
  McapReader& operator=(const McapReader&) = delete;

  /// Opens `path`: through the summary when it is intact, else by a linear scan that checks
  /// every chunk (damage() says what broke). Throws BagError NOT_MCAP for a file that does
  /// not begin with the MCAP magic, IO when it cannot be read.
  void open(const std::filesystem::path& path);

  const std::filesystem::path& path() const { return path_; }
  uint64_t fileSize() const { return size_; }
  const Header& header() const { return header_; }
  /// True when the footer and summary were intact and used; false after a linear scan.
  bool indexed() const { return indexed_; }
  const std::map<uint16_t, Schema>& schemas() const { return schemas_; }
  const std::map<uint16_t, Channel>& channels() const { return channels_; }
  /// From the summary, or counted from what the scan read.
  const Statistics& statistics() const { return statistics_; }
  /// One per Chunk record, in file order (after a scan: rebuilt from the chunks found).
  const std::vector<ChunkIndex>& chunkIndexes() const { return chunks_; }
  /// Chunks known to be damaged so far (all of them once verify() or a scan has run).
  size_t damagedChunks() const;
  const std::vector<Metadata>& metadata() const { return metadata_; }
  uint32_t attachmentCount() const { return attachment_count_; }
  /// Everything found wrong so far, in the order found.
  const std::vector<Damage>& damage() const { return damage_; }

  /// Messages in log-time order; see ReadFilter.
  MessageIterator messages(const ReadFilter& filter = {});
  /// All of them at once (tests, small bags).
  std::vector<BagMessage> readMessages(const ReadFilter& filter = {});
  /// Reads every chunk and checks its CRC, and the data section's CRC; adds what is wrong
  /// to damage(). Returns true when nothing is.
  bool verify();

 private:
  friend class MessageIterator;
  enum class ChunkState : uint8_t { UNCHECKED, INTACT, DAMAGED };
  struct LoadedChunk {
    std::shared_ptr<const std::vector<uint8_t>> records;
    std::vector<MessageIterator::Entry> entries;  // in record order
  };

  std::vector<uint8_t> readAt(uint64_t offset, uint64_t size) const;
  uint32_t crcOfRange(uint32_t crc, uint64_t offset, uint64_t size) const;
  void addDamage(uint64_t offset, const std::string& text);
  bool readSummary();
  bool checkSummaryIndexes(uint64_t summary_start);
  void readMetadataRecords();
  void statisticsFromMessageIndexes();
  void scan(uint64_t from);
  std::optional<uint64_t> findNextChunk(uint64_t from) const;
  /// A Chunk record's messages, or nullopt (and a Damage) when it is damaged. `bytes` is the
  /// whole record when the caller has read it already.
  std::optional<LoadedChunk> loadChunk(size_t chunk, const std::vector<uint8_t>* bytes = nullptr);
  void registerSchema(Schema schema);
  void registerChannel(Channel channel);
  void countScanned(const LoadedChunk& chunk);

  std::filesystem::path path_;
  int fd_ = -1;
  uint64_t size_ = 0;
  Header header_;
  bool indexed_ = false;
  std::map<uint16_t, Schema> schemas_;
  std::map<uint16_t, Channel> channels_;
  Statistics statistics_;
  std::vector<ChunkIndex> chunks_;
  std::vector<ChunkState> chunk_states_;
  std::vector<MessageIterator::Entry> loose_;  // Message records outside chunks
  std::vector<Metadata> metadata_;
  uint32_t attachment_count_ = 0;
  std::optional<uint64_t> data_end_;  // offset of the Data End record
  uint32_t data_crc_ = 0;             // as the Data End record says
  bool data_crc_checked_ = false;
  std::vector<Damage> damage_;
};

}  // namespace auv::bag
