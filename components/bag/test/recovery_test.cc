// Truncated and damaged files: every cut gives exactly the messages of the chunks it left
// whole, flipped bytes are caught by the CRCs with the place named, a damaged length field is
// skipped, a writer that dies leaves a readable `.part` file, and no damage makes the reader
// crash.
#include <gtest/gtest.h>

#include <sched.h>
#include <sys/mount.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <set>

#include "auv/bag/bag_error.h"
#include "auv/bag/bag_info.h"
#include "auv/bag/mcap_reader.h"
#include "bag_test_util.h"

namespace auv::bag {
namespace {

using namespace testing;

/// A bag written once, with what its reader says about each chunk.
struct Reference {
  fs::path path;
  std::vector<uint8_t> bytes;
  struct Read {
    Written message;
    uint16_t channel_id;
    uint64_t chunk_offset;
  };
  std::vector<Read> messages;  // in log-time order (a BagMessage points into its reader)
  std::vector<ChunkIndex> chunks;
  std::vector<uint64_t> record_starts;  // top-level records, and the trailing magic
};

Reference makeReference(const fs::path& dir, const std::string& compression, size_t count) {
  Reference ref;
  ref.path = dir / ("reference_" + compression + ".mcap");
  McapWriterOptions options;
  options.compression = compression;
  options.chunk_size = 8 * 1024;
  writeBag(ref.path, someMessages(count, 3, 800, 21), options);
  ref.bytes = readFile(ref.path);
  McapReader reader;
  reader.open(ref.path);
  EXPECT_TRUE(reader.indexed());
  for (const BagMessage& m : reader.readMessages()) {
    ref.messages.push_back(Reference::Read{asWritten(m), m.channel->id, m.chunk_offset});
  }
  ref.chunks = reader.chunkIndexes();
  for (uint64_t at = 8; at + 8 < ref.bytes.size();) {
    ref.record_starts.push_back(at);
    at += 9 + readU64(&ref.bytes[at + 1]);
  }
  ref.record_starts.push_back(ref.bytes.size() - 8);
  return ref;
}

/// The messages of `ref` whose chunk lies whole in the first `cut` bytes.
std::vector<Written> intactUpTo(const Reference& ref, uint64_t cut) {
  std::vector<Written> out;
  for (const Reference::Read& m : ref.messages) {
    for (const ChunkIndex& chunk : ref.chunks) {
      if (chunk.chunk_start_offset == m.chunk_offset &&
          chunk.chunk_start_offset + chunk.chunk_length <= cut) {
        out.push_back(m.message);
      }
    }
  }
  return out;
}

class Truncation : public ::testing::TestWithParam<std::string> {};

TEST_P(Truncation, KeepsExactlyTheChunksBeforeTheCut) {
  TempDir dir("truncation");
  const Reference ref = makeReference(dir.path(), GetParam(), 300);
  ASSERT_GT(ref.chunks.size(), 8u);
  std::set<uint64_t> cuts = {0, 1, 7, 8, 9, 12};
  for (size_t i = 0; i < ref.record_starts.size(); ++i) {
    const uint64_t start = ref.record_starts[i];
    const uint64_t end =
        i + 1 < ref.record_starts.size() ? ref.record_starts[i + 1] : ref.bytes.size();
    for (uint64_t cut : {start, start + 1, start + 9, (start + end) / 2, end - 1}) cuts.insert(cut);
  }
  const fs::path cut_path = dir.path() / "cut.mcap";
  size_t checked = 0;
  for (const uint64_t cut : cuts) {
    if (cut > ref.bytes.size()) continue;
    SCOPED_TRACE("cut at byte " + std::to_string(cut) + " of " + std::to_string(ref.bytes.size()));
    writeFile(cut_path, ref.bytes.data(), cut);
    McapReader reader;
    if (cut < 8) {
      EXPECT_THROW(reader.open(cut_path), BagError);
      continue;
    }
    reader.open(cut_path);
    EXPECT_EQ(asWritten(reader.readMessages()), intactUpTo(ref, cut)) << damageText(reader);
    if (cut < ref.bytes.size()) {
      ASSERT_FALSE(reader.damage().empty());
      EXPECT_FALSE(reader.indexed());
    } else {
      EXPECT_TRUE(reader.damage().empty()) << damageText(reader);
    }
    // A cut inside a chunk is named with the chunk's first byte.
    for (const ChunkIndex& chunk : ref.chunks) {
      const uint64_t start = chunk.chunk_start_offset;
      if (cut >= start + 9 && cut < start + chunk.chunk_length) {
        EXPECT_NE(damageText(reader).find("truncated at byte " + std::to_string(cut) +
                                          " inside a Chunk record that starts at byte " +
                                          std::to_string(start)),
                  std::string::npos)
            << damageText(reader);
      }
    }
    ++checked;
  }
  EXPECT_GT(checked, 100u);
}

INSTANTIATE_TEST_SUITE_P(Compressions, Truncation, ::testing::Values("none", "zstd", "lz4"));

class FlippedByte : public ::testing::TestWithParam<std::string> {};

TEST_P(FlippedByte, InAChunkIsCaughtAndNamed) {
  TempDir dir("flip");
  const Reference ref = makeReference(dir.path(), GetParam(), 300);
  const ChunkIndex& victim = ref.chunks[ref.chunks.size() / 2];
  std::vector<uint8_t> bytes = ref.bytes;
  // A byte in the middle of the chunk's compressed records.
  bytes[victim.chunk_start_offset + victim.chunk_length - victim.compressed_size / 2] ^= 0x5A;
  const fs::path path = dir.path() / "flipped.mcap";
  writeFile(path, bytes.data(), bytes.size());

  McapReader reader;
  reader.open(path);
  EXPECT_TRUE(reader.indexed());  // the summary is intact
  std::vector<Written> expected;
  for (const Reference::Read& m : ref.messages) {
    if (m.chunk_offset != victim.chunk_start_offset) expected.push_back(m.message);
  }
  EXPECT_EQ(asWritten(reader.readMessages()), expected);
  const std::string where = "chunk at byte " + std::to_string(victim.chunk_start_offset) + ": ";
  ASSERT_EQ(reader.damage().size(), 1u) << damageText(reader);
  EXPECT_EQ(reader.damage()[0].offset, victim.chunk_start_offset);
  EXPECT_EQ(reader.damage()[0].text.rfind(where, 0), 0u) << damageText(reader);
  if (GetParam() == "none") {
    EXPECT_NE(damageText(reader).find("CRC mismatch"), std::string::npos) << damageText(reader);
  }
  EXPECT_EQ(reader.damagedChunks(), 1u);
  EXPECT_FALSE(reader.verify());
  EXPECT_NE(damageText(reader).find("data section CRC mismatch"), std::string::npos)
      << damageText(reader);
}

INSTANTIATE_TEST_SUITE_P(Compressions, FlippedByte, ::testing::Values("none", "zstd", "lz4"));

TEST(Recovery, AFlippedByteInTheSummaryFallsBackToTheScan) {
  TempDir dir("summary");
  const Reference ref = makeReference(dir.path(), "zstd", 200);
  std::vector<uint8_t> bytes = ref.bytes;
  const uint64_t summary_start = readU64(&bytes[bytes.size() - kMagicSize - kFooterContentSize]);
  bytes[summary_start + 20] ^= 0x01;
  const fs::path path = dir.path() / "summary.mcap";
  writeFile(path, bytes.data(), bytes.size());
  McapReader reader;
  reader.open(path);
  EXPECT_FALSE(reader.indexed());
  EXPECT_EQ(asWritten(reader.readMessages()), intactUpTo(ref, ref.bytes.size()));
  ASSERT_EQ(reader.damage().size(), 1u) << damageText(reader);
  EXPECT_EQ(reader.damage()[0].text.rfind(
                "summary at byte " + std::to_string(summary_start) + ": CRC mismatch", 0),
            0u)
      << damageText(reader);
  EXPECT_EQ(reader.statistics().message_count, ref.messages.size());
  EXPECT_EQ(reader.channels().size(), 3u);
  EXPECT_EQ(reader.metadata().size(), 1u);
}

TEST(Recovery, ADamagedLengthIsSkippedToTheNextChunk) {
  TempDir dir("length");
  const Reference ref = makeReference(dir.path(), "lz4", 300);
  std::vector<uint8_t> bytes = ref.bytes;
  bytes.resize(bytes.size() - 4);  // no footer: the scan reads it
  const ChunkIndex& victim = ref.chunks[3];
  bytes[victim.chunk_start_offset + 8] = 0x7F;  // the length's top byte: far past the end
  const fs::path path = dir.path() / "length.mcap";
  writeFile(path, bytes.data(), bytes.size());
  McapReader reader;
  reader.open(path);
  std::vector<Written> expected;
  for (const Reference::Read& m : ref.messages) {
    if (m.chunk_offset != victim.chunk_start_offset) expected.push_back(m.message);
  }
  EXPECT_EQ(asWritten(reader.readMessages()), expected);
  EXPECT_NE(damageText(reader).find("Chunk record at byte " +
                                    std::to_string(victim.chunk_start_offset) + " declares"),
            std::string::npos)
      << damageText(reader);
  EXPECT_NE(damageText(reader).find("skipped to the next chunk, at byte " +
                                    std::to_string(ref.chunks[4].chunk_start_offset)),
            std::string::npos)
      << damageText(reader);
}

TEST(Recovery, AWriterThatDiesLeavesItsCompleteChunks) {
  TempDir dir("crash");
  McapWriterOptions options;
  options.chunk_size = 4096;
  McapWriter writer(options);
  writer.open(dir.path() / "live.mcap");
  const uint16_t channel = writer.addChannel(0, "/sonar", "cdr", {{"qos", "sensor_data"}});
  std::vector<Written> written;
  size_t in_chunks = 0;  // messages in the chunks written out so far
  for (uint32_t i = 0; i < 150; ++i) {
    written.push_back(Written{"/sonar", i, 5000 + i, 5000 + i, payload(100 + i, i)});
    const uint64_t chunks = writer.stats().chunks;
    writer.write(channel, i, 5000 + i, 5000 + i, written.back().data);
    if (writer.stats().chunks > chunks) in_chunks = written.size();
  }
  ASSERT_GT(in_chunks, 0u);
  ASSERT_LT(in_chunks, written.size());
  // What a crash now leaves on disk: the `.part` file as it is.
  const fs::path crashed = dir.path() / "crashed.mcap";
  fs::copy_file(dir.path() / "live.mcap.part", crashed);
  {
    McapReader reader;
    reader.open(crashed);
    EXPECT_FALSE(reader.indexed());
    EXPECT_EQ(asWritten(reader.readMessages()),
              std::vector<Written>(written.begin(), written.begin() + in_chunks));
    EXPECT_NE(damageText(reader).find("ends without a Data End record"), std::string::npos)
        << damageText(reader);
  }
  writer.flush();  // what a recorder's timer does: now every message is on disk
  fs::copy_file(dir.path() / "live.mcap.part", crashed, fs::copy_options::overwrite_existing);
  McapReader reader;
  reader.open(crashed);
  EXPECT_EQ(asWritten(reader.readMessages()), written);
  EXPECT_EQ(reader.channels().at(channel).metadata.at("qos"), "sensor_data");
  writer.close();
}

// A recording that fills its disk: the write that fails says so (BagError IO, the system's
// reason), and the `.part` file keeps every chunk written before it, readable. The disk is a
// 64 KiB tmpfs in a mount namespace of this process (needs CAP_SYS_ADMIN: root, as CI runs).
TEST(Recovery, AFullDiskKeepsTheChunksWrittenBefore) {
  TempDir dir("full");
  if (::unshare(CLONE_NEWNS) != 0 ||
      ::mount(nullptr, "/", nullptr, MS_REC | MS_PRIVATE, nullptr) != 0 ||
      ::mount("tmpfs", dir.path().c_str(), "tmpfs", 0, "size=64k") != 0) {
    GTEST_SKIP() << "a private tmpfs needs CAP_SYS_ADMIN (run as root): " << std::strerror(errno);
  }
  McapWriterOptions options;
  options.chunk_size = 4096;
  McapWriter writer(options);
  writer.open(dir.path() / "live.mcap");
  const uint16_t channel = writer.addChannel(0, "/sonar", "cdr", {{"qos", "sensor_data"}});
  std::vector<Written> written;
  std::size_t in_chunks = 0;
  std::string failure;
  for (uint32_t i = 0; i < 100000 && failure.empty(); ++i) {
    written.push_back(Written{"/sonar", i, 5000 + i, 5000 + i, payload(300, i)});
    const uint64_t chunks = writer.stats().chunks;
    try {
      writer.write(channel, i, 5000 + i, 5000 + i, written.back().data);
    } catch (const BagError& error) {
      EXPECT_EQ(error.kind(), BagError::Kind::IO);
      failure = error.what();
    }
    if (failure.empty() && writer.stats().chunks > chunks) in_chunks = written.size();
  }
  ASSERT_FALSE(failure.empty()) << "64 KiB never filled";
  EXPECT_NE(failure.find("No space left"), std::string::npos) << failure;
  EXPECT_NE(failure.find("live.mcap.part"), std::string::npos) << failure;
  ASSERT_GT(in_chunks, 0u);
  McapReader reader;
  reader.open(dir.path() / "live.mcap.part");
  EXPECT_EQ(asWritten(reader.readMessages()),
            std::vector<Written>(written.begin(), written.begin() + in_chunks));
  // It ends with the last whole record, not with a torn part of the failed one.
  EXPECT_EQ(damageText(reader).find("inside a"), std::string::npos) << damageText(reader);
  // The writer closed the file when the write failed: it is never renamed to the final name.
  EXPECT_FALSE(writer.isOpen());
  EXPECT_NO_THROW(writer.close());
  EXPECT_FALSE(fs::exists(dir.path() / "live.mcap"));
  EXPECT_TRUE(fs::exists(dir.path() / "live.mcap.part"));
  ::umount2(dir.path().c_str(), MNT_DETACH);
}

TEST(Recovery, NoDamageMakesItCrash) {
  TempDir dir("fuzz");
  const Reference ref = makeReference(dir.path(), "zstd", 150);
  // Keyed by channel id and sequence: records outside chunks (a Channel's topic) have no CRC
  // of their own, so a flipped topic can be read as it is; message bytes never can.
  std::map<std::pair<uint16_t, uint32_t>, const Written*> by_key;
  for (const Reference::Read& m : ref.messages) {
    by_key[{m.channel_id, m.message.sequence}] = &m.message;
  }
  std::mt19937 generator(77);
  const fs::path path = dir.path() / "fuzz.mcap";
  for (int round = 0; round < 300; ++round) {
    std::vector<uint8_t> bytes = ref.bytes;
    const int flips = 1 + static_cast<int>(generator() % 8);
    for (int f = 0; f < flips; ++f)
      bytes[8 + generator() % (bytes.size() - 8)] = generator() & 0xFF;
    if (generator() % 2) bytes.resize(8 + generator() % (bytes.size() - 8));
    writeFile(path, bytes.data(), bytes.size());
    SCOPED_TRACE("round " + std::to_string(round));
    McapReader reader;
    try {
      reader.open(path);
    } catch (const BagError&) {
      continue;  // a clean refusal is fine
    }
    uint64_t last = 0;
    for (const BagMessage& m : reader.readMessages()) {
      // Whatever is read was written: a damaged chunk gives nothing, never garbage.
      const auto key = std::make_pair(m.channel->id, m.message.sequence);
      ASSERT_TRUE(by_key.count(key)) << m.channel->id << " " << m.message.sequence;
      EXPECT_EQ(m.message.data, by_key[key]->data);
      EXPECT_EQ(m.message.log_time, by_key[key]->log_time);
      EXPECT_EQ(m.message.publish_time, by_key[key]->publish_time);
      EXPECT_GE(m.message.log_time, last);
      last = m.message.log_time;
    }
    reader.verify();
    EXPECT_FALSE(formatInfo(info(path, true)).empty());
  }
}

}  // namespace
}  // namespace auv::bag
