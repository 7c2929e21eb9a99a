// The reader on whole files: message indexes as written, log-time order across chunks whose
// times overlap, topic and time filters, files that are not MCAP.
#include "auv/bag/mcap_reader.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "auv/bag/bag_error.h"
#include "auv/bag/compression.h"
#include "bag_test_util.h"

namespace auv::bag {
namespace {

using namespace testing;

/// Parses the records of `bytes` from `begin` to `end` (opcode, offset, content).
struct RawRecord {
  uint8_t opcode;
  uint64_t offset;
  const uint8_t* content;
  uint64_t length;
};
std::vector<RawRecord> rawRecords(const std::vector<uint8_t>& bytes, uint64_t begin, uint64_t end) {
  std::vector<RawRecord> records;
  for (uint64_t at = begin; at < end;) {
    const uint64_t length = readU64(&bytes[at + 1]);
    records.push_back(RawRecord{bytes[at], at, &bytes[at + 9], length});
    at += 9 + length;
  }
  return records;
}

class MessageIndexes : public ::testing::TestWithParam<std::string> {};

TEST_P(MessageIndexes, PointAtEachMessageOfTheirChannel) {
  TempDir dir("index");
  const fs::path path = dir.path() / "index.mcap";
  McapWriterOptions options;
  options.compression = GetParam();
  options.chunk_size = 8 * 1024;
  // Out-of-order log times inside chunks: the index entries are sorted, offsets still right.
  std::vector<Written> messages = someMessages(400, 4, 500, 9);
  std::mt19937 generator(3);
  for (Written& w : messages) w.log_time = 1000 + generator() % 100000;
  writeBag(path, messages, options);

  McapReader reader;
  reader.open(path);
  const std::vector<uint8_t> bytes = readFile(path);
  uint64_t indexed_messages = 0;
  for (const ChunkIndex& chunk : reader.chunkIndexes()) {
    const std::vector<RawRecord> records =
        rawRecords(bytes, chunk.chunk_start_offset, chunk.chunk_start_offset + chunk.chunk_length);
    ASSERT_EQ(records.size(), 1u);
    ASSERT_EQ(records[0].opcode, uint8_t(Opcode::CHUNK));
    const ChunkHeader header = parseChunkHeader(records[0].content, records[0].length);
    const std::vector<uint8_t> uncompressed =
        decompress(header.compression, records[0].content + header.records_offset,
                   header.records_size, header.uncompressed_size);
    // The Message Index records follow the chunk, one per channel, where the index says.
    const uint64_t after = chunk.chunk_start_offset + chunk.chunk_length;
    const std::vector<RawRecord> indexes =
        rawRecords(bytes, after, after + chunk.message_index_length);
    ASSERT_EQ(indexes.size(), chunk.message_index_offsets.size());
    std::set<uint64_t> seen_offsets;
    for (const RawRecord& record : indexes) {
      ASSERT_EQ(record.opcode, uint8_t(Opcode::MESSAGE_INDEX));
      const MessageIndex index = parseMessageIndex(record.content, record.length);
      EXPECT_EQ(chunk.message_index_offsets.at(index.channel_id), record.offset);
      EXPECT_TRUE(std::is_sorted(index.entries.begin(), index.entries.end(),
                                 [](auto& a, auto& b) { return a.first < b.first; }));
      for (const auto& [log_time, offset] : index.entries) {
        ASSERT_LT(offset + 9, uncompressed.size());
        ASSERT_EQ(uncompressed[offset], uint8_t(Opcode::MESSAGE));
        const Message message =
            parseMessage(&uncompressed[offset + 9], readU64(&uncompressed[offset + 1]), false);
        EXPECT_EQ(message.channel_id, index.channel_id);
        EXPECT_EQ(message.log_time, log_time);
        EXPECT_GE(log_time, chunk.message_start_time);
        EXPECT_LE(log_time, chunk.message_end_time);
        EXPECT_TRUE(seen_offsets.insert(offset).second);
        ++indexed_messages;
      }
    }
  }
  EXPECT_EQ(indexed_messages, messages.size());
  EXPECT_EQ(asWritten(reader.readMessages()), inTimeOrder(messages));
}

INSTANTIATE_TEST_SUITE_P(Compressions, MessageIndexes, ::testing::Values("none", "zstd", "lz4"));

TEST(McapReader, MergesChunksWhoseTimesOverlap) {
  TempDir dir("overlap");
  const fs::path path = dir.path() / "overlap.mcap";
  // Topic a's messages first, then topic b's over the same span, then a late burst with
  // times going backwards: nearly every chunk overlaps others.
  std::vector<Written> messages;
  for (uint32_t i = 0; i < 300; ++i) {
    messages.push_back(Written{"/a", i, 1000 + 10 * i, 1000 + 10 * i, payload(300, i)});
  }
  for (uint32_t i = 0; i < 300; ++i) {
    messages.push_back(Written{"/b", i, 1005 + 10 * i, 1005 + 10 * i, payload(200, 500 + i)});
  }
  for (uint32_t i = 0; i < 100; ++i) {
    const uint64_t t = 4000 - 30 * i;  // some equal to /a's times: ties in file order
    messages.push_back(Written{"/c", i, t, t, payload(100, 900 + i)});
  }
  McapWriterOptions options;
  options.chunk_size = 4096;
  writeBag(path, messages, options);

  McapReader reader;
  reader.open(path);
  ASSERT_GT(reader.chunkIndexes().size(), 20u);
  const std::vector<Written> read = asWritten(reader.readMessages());
  EXPECT_EQ(read, inTimeOrder(messages));

  // The same order through the iterator, one message at a time.
  MessageIterator iterator = reader.messages();
  size_t n = 0;
  uint64_t last = 0;
  while (auto message = iterator.next()) {
    EXPECT_GE(message->message.log_time, last);
    last = message->message.log_time;
    ASSERT_NE(message->schema, nullptr);
    EXPECT_EQ(message->schema->encoding, "omgidl");
    EXPECT_NE(message->chunk_offset, 0u);
    ++n;
  }
  EXPECT_EQ(n, messages.size());
}

TEST(McapReader, FiltersByTopicAndTime) {
  TempDir dir("filter");
  const fs::path path = dir.path() / "filter.mcap";
  const std::vector<Written> messages = someMessages(900, 3, 400, 4);
  McapWriterOptions options;
  options.chunk_size = 4096;
  writeBag(path, messages, options);
  McapReader reader;
  reader.open(path);

  auto expected = [&](const std::set<std::string>& topics, uint64_t start, uint64_t end) {
    std::vector<Written> out;
    for (const Written& w : messages) {
      if ((topics.empty() || topics.count(w.topic)) && w.log_time >= start && w.log_time <= end) {
        out.push_back(w);
      }
    }
    return out;
  };
  ReadFilter filter;
  filter.topics = {"/topic_2"};
  EXPECT_EQ(asWritten(reader.readMessages(filter)), expected({"/topic_2"}, 0, UINT64_MAX));
  filter.topics = {"/topic_0", "/topic_1"};
  filter.start_ns = messages[100].log_time;
  filter.end_ns = messages[500].log_time;  // both ends included
  EXPECT_EQ(asWritten(reader.readMessages(filter)),
            expected({"/topic_0", "/topic_1"}, filter.start_ns, filter.end_ns));
  filter.topics = {"/nothing"};
  EXPECT_TRUE(reader.readMessages(filter).empty());
  filter.topics.clear();
  filter.start_ns = messages.back().log_time + 1;
  filter.end_ns = UINT64_MAX;
  EXPECT_TRUE(reader.readMessages(filter).empty());
  filter.start_ns = filter.end_ns = messages[333].log_time;
  EXPECT_EQ(asWritten(reader.readMessages(filter)), std::vector<Written>{messages[333]});
}

TEST(McapReader, RefusesWhatIsNotMcap) {
  TempDir dir("notmcap");
  auto kind = [&](const std::string& name, const std::string& content) {
    const fs::path path = dir.path() / name;
    writeFile(path, reinterpret_cast<const uint8_t*>(content.data()), content.size());
    McapReader reader;
    try {
      reader.open(path);
    } catch (const BagError& e) {
      EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
      return e.kind();
    }
    ADD_FAILURE() << name << " opened";
    return BagError::Kind::IO;
  };
  EXPECT_EQ(kind("empty.mcap", ""), BagError::Kind::NOT_MCAP);
  EXPECT_EQ(kind("short.mcap", "\x89MC"), BagError::Kind::NOT_MCAP);
  EXPECT_EQ(kind("text.mcap", "this is a text file, not a bag"), BagError::Kind::NOT_MCAP);
  McapReader reader;
  try {
    reader.open(dir.path() / "missing.mcap");
    FAIL();
  } catch (const BagError& e) {
    EXPECT_EQ(e.kind(), BagError::Kind::NOT_FOUND);
    EXPECT_EQ(e.exitCode(), 2);
    EXPECT_NE(std::string(e.what()).find("missing.mcap"), std::string::npos);
  }
}

}  // namespace
}  // namespace auv::bag
