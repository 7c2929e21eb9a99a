// McapReader's linear scan: the data section record by record from the start, for files
// whose footer or summary is missing or damaged (or that have none). Every chunk is read and
// checked; a record whose length runs past the end is where the file breaks, unless another
// chunk can be found after it (a damaged length field rather than a cut).

#include <cstring>

#include "auv/bag/compression.h"
#include "auv/bag/mcap_reader.h"
#include "auv/bag/record_scan.h"

namespace auv::bag {

namespace {

std::string str(uint64_t value) { return std::to_string(value); }

constexpr uint64_t kChunkFixedSize = 8 + 8 + 8 + 4 + 4 + 8;  // Chunk content without strings

/// True when the `available` bytes at `p` (a position `remaining` bytes from the end of the
/// file) begin a plausible Chunk record: consistent lengths, a known compression.
bool plausibleChunk(const uint8_t* p, uint64_t available, uint64_t remaining) {
  if (available < kRecordHeaderSize + kChunkFixedSize || p[0] != uint8_t(Opcode::CHUNK)) {
    return false;
  }
  const uint64_t length = readU64(p + 1);
  if (length > remaining - kRecordHeaderSize || length < kChunkFixedSize) return false;
  const uint8_t* c = p + kRecordHeaderSize;
  if (readU64(c) > readU64(c + 8) || readU64(c + 16) > kMaxChunkBytes) return false;
  const uint32_t name_size = readU32(c + 28);
  if (name_size != 0 && name_size != 3 && name_size != 4) return false;
  if (available < kRecordHeaderSize + kChunkFixedSize + name_size) return false;
  const std::string name(reinterpret_cast<const char*>(c + 32), name_size);
  if (!name.empty() && name != "lz4" && name != "zstd") return false;
  return readU64(c + 32 + name_size) == length - kChunkFixedSize - name_size;
}

}  // namespace

std::optional<uint64_t> McapReader::findNextChunk(uint64_t from) const {
  constexpr uint64_t kBlock = 1 << 20;
  constexpr uint64_t kOverlap = kRecordHeaderSize + kChunkFixedSize + 4;
  for (uint64_t block_at = from; block_at < size_; block_at += kBlock) {
    const std::vector<uint8_t> block =
        readAt(block_at, std::min(kBlock + kOverlap, size_ - block_at));
    const uint64_t candidates = std::min<uint64_t>(kBlock, block.size());
    for (uint64_t i = 0; i < candidates; ++i) {
      if (block[i] != uint8_t(Opcode::CHUNK)) continue;
      if (plausibleChunk(block.data() + i, block.size() - i, size_ - block_at - i)) {
        return block_at + i;
      }
    }
  }
  return std::nullopt;
}

void McapReader::countScanned(const LoadedChunk& chunk) {
  Statistics& s = statistics_;
  for (const MessageIterator::Entry& entry : chunk.entries) {
    s.message_start_time =
        s.message_count == 0 ? entry.log_time : std::min(s.message_start_time, entry.log_time);
    s.message_end_time =
        s.message_count == 0 ? entry.log_time : std::max(s.message_end_time, entry.log_time);
    ++s.message_count;
    ++s.channel_message_counts[entry.channel_id];
  }
}

void McapReader::scan(uint64_t from) {
  schemas_.clear();
  channels_.clear();
  chunks_.clear();
  chunk_states_.clear();
  loose_.clear();
  metadata_.clear();
  statistics_ = Statistics{};
  attachment_count_ = 0;
  data_end_.reset();
  indexed_ = false;

  uint32_t crc = crcOfRange(0, 0, from);  // the data section CRC covers the magic and header
  bool crc_whole = true;                  // false once bytes were skipped
  uint64_t pos = from;
  bool done = false;
  while (!done) {
    if (pos == size_) {
      addDamage(size_, "truncated at byte " + str(size_) +
                           ": the file ends without a Data End record and footer (a recording "
                           "that was not closed?)");
      break;
    }
    if (size_ - pos < kRecordHeaderSize) {
      addDamage(size_, "truncated at byte " + str(size_) +
                           " inside the header of a record that starts at byte " + str(pos));
      break;
    }
    const std::vector<uint8_t> head = readAt(pos, kRecordHeaderSize);
    const uint8_t op = head[0];
    const uint64_t length = readU64(&head[1]);
    const uint64_t left = size_ - pos - kRecordHeaderSize;
    if (op == 0 || length > left) {
      const std::string what = op == 0
                                   ? "byte " + str(pos) + ": not an MCAP record (opcode 0)"
                                   : opcodeName(op) + " record at byte " + str(pos) + " declares " +
                                         str(length) + " bytes, " + str(left) + " are left";
      const std::optional<uint64_t> next = findNextChunk(pos + 1);
      if (next) {
        addDamage(pos, what + "; skipped to the next chunk, at byte " + str(*next));
        pos = *next;
        crc_whole = false;
        continue;
      }
      if (op == 0) {
        addDamage(pos, what + "; no chunk after it");
      } else {
        addDamage(size_, "truncated at byte " + str(size_) + " inside a " + opcodeName(op) +
                             " record that starts at byte " + str(pos) + " (declares " +
                             str(length) + " bytes, " + str(left) + " present)");
      }
      break;
    }
    const uint64_t record_size = kRecordHeaderSize + length;
    const bool wanted = op == uint8_t(Opcode::CHUNK) || op == uint8_t(Opcode::SCHEMA) ||
                        op == uint8_t(Opcode::CHANNEL) || op == uint8_t(Opcode::MESSAGE) ||
                        op == uint8_t(Opcode::METADATA) || op == uint8_t(Opcode::DATA_END);
    if (!wanted || record_size > kMaxChunkBytes) {
      if (wanted) addDamage(pos, opcodeName(op) + " record at byte " + str(pos) + ": too large");
      if (op == uint8_t(Opcode::ATTACHMENT)) ++attachment_count_;
      done = op == uint8_t(Opcode::FOOTER);  // a data section without Data End
      if (!done) crc = crcOfRange(crc, pos, record_size);
      pos += record_size;
      continue;
    }
    const std::vector<uint8_t> bytes = readAt(pos, record_size);
    const uint8_t* content = bytes.data() + kRecordHeaderSize;
    try {
      switch (static_cast<Opcode>(op)) {
        case Opcode::CHUNK: {
          const ChunkHeader header = parseChunkHeader(content, length);
          ChunkIndex index;
          index.message_start_time = header.message_start_time;
          index.message_end_time = header.message_end_time;
          index.chunk_start_offset = pos;
          index.chunk_length = record_size;
          index.compression = header.compression;
          index.compressed_size = header.records_size;
          index.uncompressed_size = header.uncompressed_size;
          chunks_.push_back(index);
          chunk_states_.push_back(ChunkState::UNCHECKED);
          if (auto loaded = loadChunk(chunks_.size() - 1, &bytes)) countScanned(*loaded);
          break;
        }
        case Opcode::SCHEMA:
          registerSchema(parseSchema(content, length));
          break;
        case Opcode::CHANNEL:
          registerChannel(parseChannel(content, length));
          break;
        case Opcode::METADATA:
          metadata_.push_back(parseMetadata(content, length));
          break;
        case Opcode::MESSAGE: {
          const Message message = parseMessage(content, length, false);
          if (!channels_.count(message.channel_id)) {
            throw ParseError("channel " + str(message.channel_id) +
                             ", which no Channel record defines");
          }
          loose_.push_back(MessageIterator::Entry{message.log_time, pos + kRecordHeaderSize, length,
                                                  message.channel_id});
          countScanned(LoadedChunk{nullptr, {loose_.back()}});
          break;
        }
        case Opcode::DATA_END: {
          const uint32_t stored = parseDataEnd(content, length);
          data_end_ = pos;
          data_crc_ = stored;
          data_crc_checked_ = true;
          if (stored != 0 && crc_whole && stored != crc) {
            addDamage(0, "data section CRC mismatch (bytes 0 to " + str(pos) + " give " +
                             hex32(crc) + ", the Data End record says " + hex32(stored) + ")");
          }
          done = true;
          break;
        }
        default:
          break;
      }
    } catch (const ParseError& e) {
      const std::string kind = op == uint8_t(Opcode::CHUNK) ? "chunk" : opcodeName(op) + " record";
      addDamage(pos, kind + " at byte " + str(pos) + ": " + e.what());
    }
    crc = crc32Update(crc, bytes.data(), bytes.size());
    pos += record_size;
  }
  Statistics& s = statistics_;
  s.schema_count = static_cast<uint16_t>(schemas_.size());
  s.channel_count = static_cast<uint32_t>(channels_.size());
  s.chunk_count = static_cast<uint32_t>(chunks_.size());
  s.metadata_count = static_cast<uint32_t>(metadata_.size());
  s.attachment_count = attachment_count_;
  for (const auto& [id, channel] : channels_) s.channel_message_counts.emplace(id, 0);
}

}  // namespace auv::bag
