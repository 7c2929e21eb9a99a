// The writer: round trips for each compression, many channels, ids, the `.part` file, refusal
// to overwrite, options named by field.
#include "auv/bag/mcap_writer.h"

#include <gtest/gtest.h>

#include <functional>

#include "auv/bag/bag_error.h"
#include "auv/bag/mcap_reader.h"
#include "bag_test_util.h"

namespace auv::bag {
namespace {

using namespace testing;

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no error)";
}

class RoundTrip : public ::testing::TestWithParam<std::string> {};

TEST_P(RoundTrip, ReadsBackWhatWasWritten) {
  TempDir dir("roundtrip");
  const fs::path path = dir.path() / "bag.mcap";
  const std::vector<Written> messages = someMessages(600, 3, 3000);
  McapWriterOptions options;
  options.compression = GetParam();
  options.chunk_size = 64 * 1024;
  writeBag(path, messages, options);

  McapReader reader;
  reader.open(path);
  EXPECT_TRUE(reader.indexed());
  EXPECT_TRUE(reader.damage().empty()) << damageText(reader);
  EXPECT_EQ(reader.header().library, "auv-inspect");
  EXPECT_EQ(reader.header().profile, "");
  ASSERT_EQ(reader.schemas().size(), 1u);
  EXPECT_EQ(reader.schemas().at(1).name, "auv_msgs::msg::Blob");
  EXPECT_EQ(reader.schemas().at(1).encoding, "omgidl");
  ASSERT_EQ(reader.channels().size(), 3u);
  EXPECT_EQ(reader.channels().at(2).topic, "/topic_1");
  EXPECT_EQ(reader.channels().at(2).message_encoding, "cdr");
  EXPECT_EQ(reader.channels().at(2).metadata.at("offered_qos_profiles"), "reliable, keep last 10");
  const Statistics& s = reader.statistics();
  EXPECT_EQ(s.message_count, 600u);
  EXPECT_EQ(s.channel_message_counts.at(1), 200u);
  EXPECT_EQ(s.message_start_time, messages.front().log_time);
  EXPECT_EQ(s.message_end_time, messages.back().log_time);
  EXPECT_GT(s.chunk_count, 5u);
  EXPECT_EQ(s.chunk_count, reader.chunkIndexes().size());
  for (const ChunkIndex& chunk : reader.chunkIndexes()) {
    EXPECT_EQ(chunk.compression, GetParam() == "none" ? "" : GetParam());
  }
  ASSERT_EQ(reader.metadata().size(), 1u);
  EXPECT_EQ(reader.metadata()[0].name, "recording");
  EXPECT_EQ(reader.metadata()[0].metadata.at("mission"), "canyon");

  EXPECT_EQ(asWritten(reader.readMessages()), messages);
  EXPECT_TRUE(reader.verify()) << damageText(reader);
}

INSTANTIATE_TEST_SUITE_P(Compressions, RoundTrip, ::testing::Values("none", "zstd", "lz4"));

TEST(McapWriter, ManyChannelsKeepTheirMessages) {
  TempDir dir("channels");
  const fs::path path = dir.path() / "many.mcap";
  const std::vector<Written> messages = someMessages(3000, 300, 200, 5);
  McapWriterOptions options;
  options.chunk_size = 16 * 1024;
  writeBag(path, messages, options);
  McapReader reader;
  reader.open(path);
  ASSERT_EQ(reader.channels().size(), 300u);
  for (const auto& [id, count] : reader.statistics().channel_message_counts) {
    EXPECT_EQ(count, 10u) << "channel " << id;
  }
  EXPECT_EQ(asWritten(reader.readMessages()), messages);
  ReadFilter one;
  one.topics = {"/topic_123"};
  const std::vector<BagMessage> only = reader.readMessages(one);
  ASSERT_EQ(only.size(), 10u);
  for (size_t i = 0; i < only.size(); ++i) EXPECT_EQ(asWritten(only[i]), messages[123 + 300 * i]);
}

TEST(McapWriter, GivesTheSameIdForTheSameSchemaOrChannel) {
  TempDir dir("ids");
  McapWriter writer;
  writer.open(dir.path() / "ids.mcap");
  const uint16_t a = writer.addSchema("A", "omgidl", "struct A { long x; };");
  const uint16_t b = writer.addSchema("B", "omgidl", "struct B { long y; };");
  EXPECT_EQ(a, 1);
  EXPECT_EQ(b, 2);
  EXPECT_EQ(writer.addSchema("A", "omgidl", "struct A { long x; };"), a);
  const uint16_t c1 = writer.addChannel(a, "/a", "cdr", {{"qos", "reliable"}});
  EXPECT_EQ(writer.addChannel(a, "/a", "cdr", {{"qos", "reliable"}}), c1);
  EXPECT_NE(writer.addChannel(a, "/a", "cdr", {{"qos", "best_effort"}}), c1);
  EXPECT_NE(writer.addChannel(0, "/raw", "cdr"), c1);  // no schema
  EXPECT_NE(errorOf([&] { writer.addChannel(9, "/x", "cdr"); }).find("unknown schema id 9"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { writer.write(77, 0, 0, 0, {}); }).find("unknown channel id 77"),
            std::string::npos);
  writer.close();
}

TEST(McapWriter, WritesAPartFileRenamedAtClose) {
  TempDir dir("part");
  const fs::path path = dir.path() / "rec.mcap";
  McapWriter writer;
  writer.open(path);
  EXPECT_FALSE(fs::exists(path));
  EXPECT_TRUE(fs::exists(dir.path() / "rec.mcap.part"));
  const uint16_t channel = writer.addChannel(0, "/x", "cdr");
  writer.write(channel, 1, 10, 10, payload(100, 1));
  writer.close();
  EXPECT_TRUE(fs::exists(path));
  EXPECT_FALSE(fs::exists(dir.path() / "rec.mcap.part"));
  writer.close();  // a second close does nothing
  McapReader reader;
  reader.open(path);
  EXPECT_EQ(reader.readMessages().size(), 1u);
}

TEST(McapWriter, RefusesToOverwriteUnlessTold) {
  TempDir dir("overwrite");
  const fs::path path = dir.path() / "taken.mcap";
  const std::vector<uint8_t> before = {'k', 'e', 'e', 'p'};
  writeFile(path, before.data(), before.size());
  McapWriter writer;
  try {
    writer.open(path);
    FAIL() << "overwrote " << path;
  } catch (const BagError& e) {
    EXPECT_EQ(e.kind(), BagError::Kind::EXISTS);
    EXPECT_EQ(e.exitCode(), 2);
    EXPECT_NE(std::string(e.what()).find("'" + path.string() + "' exists"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(readFile(path), before);
  EXPECT_FALSE(fs::exists(dir.path() / "taken.mcap.part"));

  // An unfinished recording's `.part` file is kept too.
  const fs::path other = dir.path() / "other.mcap";
  writeFile(dir.path() / "other.mcap.part", before.data(), before.size());
  const std::string message = errorOf([&] { writer.open(other); });
  EXPECT_NE(message.find("other.mcap.part' exists: an unfinished recording"), std::string::npos)
      << message;
  EXPECT_EQ(readFile(dir.path() / "other.mcap.part"), before);

  McapWriterOptions options;
  options.overwrite = true;
  writeBag(path, someMessages(10, 1, 10), options);
  McapReader reader;
  reader.open(path);
  EXPECT_EQ(reader.readMessages().size(), 10u);
}

TEST(McapWriter, NamesTheBadOption) {
  auto complaint = [](auto change) {
    McapWriterOptions options;
    change(options);
    return errorOf([&] { McapWriter writer(options); });
  };
  EXPECT_NE(complaint([](auto& o) {
              o.compression = "gzip";
            }).find("compression: expected one of none, zstd, lz4, got 'gzip'"),
            std::string::npos);
  EXPECT_NE(complaint([](auto& o) { o.chunk_size = 10; }).find("chunk_size: expected an integer"),
            std::string::npos);
  EXPECT_NE(complaint([](auto& o) { o.compression_level = 25; }).find("compression_level"),
            std::string::npos);
  EXPECT_NE(complaint([](auto& o) {
              o.compression = "lz4";
              o.compression_level = 15;
            }).find("compression_level: expected an integer in [0, 12] for lz4, got 15"),
            std::string::npos);
  EXPECT_EQ(complaint([](auto&) {}), "(no error)");
  try {
    McapWriterOptions options;
    options.compression = "gzip";
    options.check();
    FAIL();
  } catch (const std::invalid_argument&) {  // exit code 2, like every options check()
  }
}

TEST(McapWriter, EmptyBagIsValid) {
  TempDir dir("empty");
  const fs::path path = dir.path() / "empty.mcap";
  McapWriter writer;
  writer.open(path);
  writer.close();
  McapReader reader;
  reader.open(path);
  EXPECT_TRUE(reader.indexed());
  EXPECT_TRUE(reader.damage().empty()) << damageText(reader);
  EXPECT_EQ(reader.statistics().message_count, 0u);
  EXPECT_TRUE(reader.readMessages().empty());
  EXPECT_TRUE(reader.verify());
}

TEST(McapWriter, LargeMessagesAndFlushMakeChunks) {
  TempDir dir("large");
  const fs::path path = dir.path() / "large.mcap";
  McapWriterOptions options;
  options.chunk_size = 4096;
  McapWriter writer(options);
  writer.open(path);
  const uint16_t channel = writer.addChannel(0, "/image", "cdr");
  const std::vector<uint8_t> big = payload(3 << 20, 3, false);
  writer.write(channel, 0, 100, 100, big);
  EXPECT_EQ(writer.stats().chunks, 1u);  // over chunk_size on its own
  writer.write(channel, 1, 200, 200, payload(10, 4));
  EXPECT_EQ(writer.stats().chunks, 1u);
  writer.flush();
  EXPECT_EQ(writer.stats().chunks, 2u);
  writer.flush();  // nothing to write
  EXPECT_EQ(writer.stats().chunks, 2u);
  EXPECT_EQ(writer.stats().messages, 2u);
  writer.close();
  McapReader reader;
  reader.open(path);
  const std::vector<BagMessage> read = reader.readMessages();
  ASSERT_EQ(read.size(), 2u);
  EXPECT_EQ(read[0].message.data, big);
  EXPECT_EQ(reader.chunkIndexes().size(), 2u);
}

TEST(McapWriter, DestructorFinishesTheFile) {
  TempDir dir("destructor");
  const fs::path path = dir.path() / "scoped.mcap";
  {
    McapWriter writer;
    writer.open(path);
    writer.write(writer.addChannel(0, "/x", "cdr"), 0, 5, 5, payload(50, 2));
  }
  McapReader reader;
  reader.open(path);
  EXPECT_TRUE(reader.indexed());
  EXPECT_EQ(reader.readMessages().size(), 1u);
}

}  // namespace
}  // namespace auv::bag
