// What `auv bag info` shows: from the summary of a whole file, from the scan of a damaged one.
#include "auv/bag/bag_info.h"

#include <gtest/gtest.h>

#include "bag_test_util.h"

namespace auv::bag {
namespace {

using namespace testing;

TEST(BagInfo, SummarisesAWholeFile) {
  TempDir dir("info");
  const fs::path path = dir.path() / "run.mcap";
  // 2026-11-27 10:00:00 UTC, one message a millisecond.
  const uint64_t t0 = 1795773600ULL * 1000000000ULL;
  const std::vector<Written> messages = someMessages(900, 3, 500, 2, t0, 1000000);
  McapWriterOptions options;
  options.chunk_size = 16 * 1024;
  writeBag(path, messages, options);

  const Summary s = info(path);
  EXPECT_TRUE(s.indexed);
  EXPECT_FALSE(s.verified);
  EXPECT_EQ(s.library, "auv-inspect");
  EXPECT_EQ(s.file_size, fs::file_size(path));
  EXPECT_EQ(s.message_count, 900u);
  EXPECT_EQ(s.start_ns, t0);
  EXPECT_EQ(s.end_ns, t0 + 899 * 1000000ULL);
  EXPECT_NEAR(s.duration_s, 0.899, 1e-9);
  ASSERT_EQ(s.channels.size(), 3u);
  EXPECT_EQ(s.channels[0].topic, "/topic_0");
  EXPECT_EQ(s.channels[0].schema_name, "auv_msgs::msg::Blob");
  EXPECT_EQ(s.channels[0].schema_encoding, "omgidl");
  EXPECT_EQ(s.channels[0].message_encoding, "cdr");
  EXPECT_EQ(s.channels[0].message_count, 300u);
  EXPECT_EQ(s.channels[0].metadata.at("offered_qos_profiles"), "reliable, keep last 10");
  EXPECT_GT(s.chunk_count, 3u);
  EXPECT_EQ(s.chunk_compressions.at("zstd"), s.chunk_count);
  EXPECT_LT(s.compressed_bytes, s.uncompressed_bytes);
  EXPECT_EQ(s.metadata_names, std::vector<std::string>{"recording"});
  EXPECT_TRUE(s.damage.empty());

  const std::string text = formatInfo(info(path, true));
  for (const char* line :
       {"messages:     900",
        "start:        2026-11-27 10:00:00.000000000 UTC (1795773600.000000000)",
        "duration:     0.899 s", "read from:    the summary", "channels:     3",
        "(1) /topic_0  300 msgs  auv_msgs::msg::Blob [omgidl] cdr",
        "offered_qos_profiles: reliable, keep last 10", "metadata:     recording",
        "damage:       none (every chunk and CRC checked)"}) {
    EXPECT_NE(text.find(line), std::string::npos) << "no '" << line << "' in\n" << text;
  }
  EXPECT_NE(text.find("chunks:       " + std::to_string(s.chunk_count) + " (zstd: "),
            std::string::npos)
      << text;
}

TEST(BagInfo, SaysWhereADamagedFileBreaks) {
  TempDir dir("info_damage");
  const fs::path path = dir.path() / "cut.mcap";
  const fs::path whole = dir.path() / "whole.mcap";
  McapWriterOptions options;
  options.chunk_size = 4096;
  options.compression = "lz4";
  writeBag(whole, someMessages(300, 2, 400, 8), options);
  std::vector<uint8_t> bytes = readFile(whole);
  McapReader reference;
  reference.open(whole);
  const ChunkIndex last = reference.chunkIndexes().back();
  const uint64_t cut = last.chunk_start_offset + 100;
  writeFile(path, bytes.data(), cut);

  const Summary s = info(path);
  EXPECT_FALSE(s.indexed);
  EXPECT_EQ(s.chunk_count, reference.chunkIndexes().size() - 1);
  EXPECT_LT(s.message_count, 300u);
  EXPECT_GT(s.message_count, 200u);
  uint64_t per_channel = 0;
  for (const ChannelSummary& c : s.channels) per_channel += c.message_count;
  EXPECT_EQ(per_channel, s.message_count);
  ASSERT_EQ(s.damage.size(), 2u);
  const std::string text = formatInfo(s);
  EXPECT_NE(text.find("read from:    a linear scan"), std::string::npos) << text;
  EXPECT_NE(text.find("damage:       2 places"), std::string::npos) << text;
  EXPECT_NE(text.find("  - no footer at the end of the file (byte " + std::to_string(cut) + ")"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("  - truncated at byte " + std::to_string(cut) +
                      " inside a Chunk record that starts at byte " +
                      std::to_string(last.chunk_start_offset)),
            std::string::npos)
      << text;
}

TEST(BagInfo, FormatsTimesAndSizes) {
  EXPECT_EQ(formatTime(1500000000ULL), "1.500000000 s");  // since boot, simulated time
  EXPECT_EQ(formatTime(946684800ULL * 1000000000ULL + 5),
            "2000-01-01 00:00:00.000000005 UTC (946684800.000000005)");
  EXPECT_EQ(formatBytes(512), "512 B");
  EXPECT_EQ(formatBytes(1536), "1.5 KiB");
  EXPECT_EQ(formatBytes(3ULL << 30), "3.0 GiB");
}

}  // namespace
}  // namespace auv::bag
