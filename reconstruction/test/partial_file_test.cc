// Partial files and their progress records (no DDS): a resume re-verifies recorded chunks from
// disk and keeps only those that match; a record of another file version is replaced; finish()
// renames only a file whose SHA-256 matches. The manifest round-trips and a broken one is named.
#include "auv/recon/transfer/partial_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <random>

#include "auv/recon/transfer/manifest.h"
#include "auv/transfer/sha256.h"

namespace auv::recon::transfer {
namespace {

namespace fs = std::filesystem;

class TempDir {
 public:
  TempDir() {
    path_ = fs::temp_directory_path() /
            ("auv_partial_" + std::to_string(::getpid()) + "_" +
             std::to_string(std::chrono::steady_clock::now().time_since_epoch().count()));
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

std::string randomBytes(size_t size, uint32_t seed) {
  std::mt19937 generator(seed);
  std::string bytes(size, '\0');
  for (auto& b : bytes) b = static_cast<char>(generator() & 0xFF);
  return bytes;
}

std::string readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void writeChunk(PartialFile& file, const std::string& bytes, size_t index) {
  const std::string chunk = bytes.substr(file.chunkOffset(index), file.chunkLength(index));
  file.writeChunk(index, reinterpret_cast<const uint8_t*>(chunk.data()), chunk.size(),
                  auv::transfer::Sha256::of(chunk.data(), chunk.size()));
}

TEST(PartialFile, ResumeReverifiesChunksOnDiskAndFinishesVerified) {
  TempDir dir;
  const std::string bytes = randomBytes(10000, 1);
  const RemoteFile remote{"left/a.mp4", bytes.size(),
                          auv::transfer::Sha256::of(bytes.data(), bytes.size())};
  const fs::path final_path = dir.path() / "left" / "a.mp4";
  {
    PartialFile file(final_path, remote, 4096);
    EXPECT_EQ(file.chunkCount(), 3u);
    EXPECT_EQ(file.chunkLength(2), 10000u - 8192u);
    writeChunk(file, bytes, 0);
    writeChunk(file, bytes, 2);
    EXPECT_EQ(file.missingBytes(), 4096u);
  }
  EXPECT_FALSE(fs::exists(final_path));
  // Interrupted mid-line: the cut record line is ignored.
  { std::ofstream(PartialFile::progressPath(final_path), std::ios::app) << "chunk 1 abc"; }
  // A bit flipped on disk in chunk 2: that chunk is fetched again.
  {
    std::fstream part(PartialFile::partPath(final_path),
                      std::ios::in | std::ios::out | std::ios::binary);
    part.seekp(9000);
    part.put(static_cast<char>(bytes[9000] ^ 0x01));
  }
  PartialFile resumed(final_path, remote, 65536);  // the record's chunk size wins
  EXPECT_EQ(resumed.chunkBytes(), 4096u);
  EXPECT_EQ(resumed.reusedChunks(), 1u);
  EXPECT_EQ(resumed.droppedChunks(), 1u);
  EXPECT_TRUE(resumed.has(0));
  EXPECT_FALSE(resumed.has(1));
  EXPECT_FALSE(resumed.has(2));
  writeChunk(resumed, bytes, 1);
  writeChunk(resumed, bytes, 2);
  resumed.finish();
  EXPECT_EQ(readFile(final_path), bytes);
  EXPECT_FALSE(fs::exists(PartialFile::partPath(final_path)));
  EXPECT_FALSE(fs::exists(PartialFile::progressPath(final_path)));
}

TEST(PartialFile, RecordOfAnotherVersionIsReplaced) {
  TempDir dir;
  const std::string old_bytes = randomBytes(5000, 2);
  const std::string new_bytes = randomBytes(5000, 3);
  const fs::path final_path = dir.path() / "a.mp4";
  {
    PartialFile file(final_path, {"a.mp4", 5000, auv::transfer::Sha256::of(old_bytes.data(), 5000)},
                     4096);
    writeChunk(file, old_bytes, 0);
  }
  PartialFile file(final_path, {"a.mp4", 5000, auv::transfer::Sha256::of(new_bytes.data(), 5000)},
                   4096);
  EXPECT_EQ(file.reusedChunks(), 0u);
  EXPECT_NE(file.startNote().find("another version"), std::string::npos) << file.startNote();
  EXPECT_EQ(file.missingBytes(), 5000u);
}

TEST(PartialFile, WrongWholeFileDigestIsNeverRenamed) {
  TempDir dir;
  const std::string bytes = randomBytes(3000, 4);
  const fs::path final_path = dir.path() / "a.mp4";
  PartialFile file(final_path, {"a.mp4", 3000, std::string(64, 'a')}, 4096);
  writeChunk(file, bytes, 0);
  EXPECT_THROW(file.finish(), VerifyError);
  EXPECT_FALSE(fs::exists(final_path));
  EXPECT_FALSE(fs::exists(PartialFile::partPath(final_path)));
}

TEST(PartialFile, WholeFileMismatchNamesTheCorruptedChunkAndKeepsTheRest) {
  // Chunks are written with the vehicle's digest and not hashed on arrival: the whole-file
  // check in finish() finds a damaged one, which alone is dropped and fetched again.
  TempDir dir;
  const std::string bytes = randomBytes(10000, 5);
  const fs::path final_path = dir.path() / "a.mp4";
  PartialFile file(final_path,
                   {"a.mp4", bytes.size(), auv::transfer::Sha256::of(bytes.data(), 10000)}, 4096);
  writeChunk(file, bytes, 0);
  std::string damaged = bytes.substr(4096, 4096);
  const std::string vehicle_digest = auv::transfer::Sha256::of(damaged.data(), damaged.size());
  damaged[7] ^= 0x01;
  file.writeChunk(1, reinterpret_cast<const uint8_t*>(damaged.data()), damaged.size(),
                  vehicle_digest);
  writeChunk(file, bytes, 2);
  EXPECT_EQ(file.finish(), std::vector<size_t>{1});
  EXPECT_FALSE(fs::exists(final_path));
  EXPECT_FALSE(file.has(1));
  EXPECT_TRUE(file.has(0));
  EXPECT_TRUE(file.has(2));
  EXPECT_EQ(file.missingBytes(), 4096u);
  writeChunk(file, bytes, 1);
  EXPECT_TRUE(file.finish().empty());
  EXPECT_EQ(readFile(final_path), bytes);
}

TEST(Manifest, RoundTripsAndNamesABrokenFile) {
  TempDir dir;
  const fs::path path = dir.path() / "manifest.json";
  {
    Manifest manifest(path);
    ManifestEntry entry;
    entry.file = "left/a.mp4";
    entry.camera = "left";
    entry.size_bytes = 12;
    entry.sha256 = std::string(64, 'b');
    entry.frame_count = 3;
    entry.end_time_s = 1.5;
    manifest.record(entry);
  }
  Manifest loaded(path);
  ASSERT_NE(loaded.find("left/a.mp4"), nullptr);
  EXPECT_EQ(loaded.find("left/a.mp4")->size_bytes, 12u);
  EXPECT_EQ(loaded.find("left/a.mp4")->frame_count, 3u);
  EXPECT_DOUBLE_EQ(loaded.find("left/a.mp4")->end_time_s, 1.5);
  { std::ofstream(path) << "{\"format\": \"auv-recordings-manifest 1\", \"recordings\": [{}]}"; }
  try {
    Manifest broken(path);
    FAIL() << "accepted a broken manifest";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("manifest.json"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace auv::recon::transfer
