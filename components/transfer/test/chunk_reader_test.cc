// The chunk reader: paths from the network cannot leave the recordings root; ranges, caps and
// files changed since they were catalogued.
#include "auv/transfer/chunk_reader.h"

#include <gtest/gtest.h>

#include "auv/transfer/testing/temp_files.h"

namespace auv::transfer {
namespace {

namespace fs = std::filesystem;
using testing::randomBytes;
using testing::TempDir;
using testing::writeFile;

ChunkError::Kind kindOf(const ChunkReader& reader, const std::string& path) {
  try {
    reader.read(path, 0, 100);
  } catch (const ChunkError& e) {
    return e.kind();
  }
  ADD_FAILURE() << "'" << path << "' was read";
  return ChunkError::Kind::IO;
}

TEST(ChunkReader, RefusesPathsOutsideTheRoot) {
  TempDir dir("paths");
  TempDir outside("outside");
  writeFile(dir.path() / "left" / "a.mp4", "inside");
  writeFile(outside.path() / "secret.mp4", "secret");
  fs::create_symlink(outside.path() / "secret.mp4", dir.path() / "left" / "link.mp4");
  fs::create_directory_symlink(outside.path(), dir.path() / "escape");
  ChunkReader reader(dir.path(), 1024);
  for (const std::string bad : {"", "/etc/passwd", "../x", "left/../../x", "left//a.mp4",
                                "left/./a.mp4", "left\\a.mp4", "left/", ".."}) {
    EXPECT_EQ(kindOf(reader, bad), ChunkError::Kind::INVALID_PATH) << "'" << bad << "'";
  }
  EXPECT_EQ(kindOf(reader, "left/link.mp4"), ChunkError::Kind::NOT_FOUND);
  EXPECT_EQ(kindOf(reader, "escape/secret.mp4"), ChunkError::Kind::NOT_FOUND);
  EXPECT_EQ(kindOf(reader, "left/none.mp4"), ChunkError::Kind::NOT_FOUND);
  EXPECT_EQ(kindOf(reader, "left"), ChunkError::Kind::NOT_FOUND);  // a folder
  try {
    reader.read("../x", 0, 1);
  } catch (const ChunkError& e) {
    EXPECT_NE(std::string(e.what()).find("file_path '../x'"), std::string::npos) << e.what();
  }
  EXPECT_EQ(reader.read("left/a.mp4", 0, 100).data.size(), 6u);
}

TEST(ChunkReader, ReadsRangesCappedAtTheMaximum) {
  TempDir dir("ranges");
  const std::string bytes = randomBytes(10000, 11);
  writeFile(dir.path() / "c" / "f.mp4", bytes);
  ChunkReader reader(dir.path(), 4096);
  Chunk chunk = reader.read("c/f.mp4", 1000, 100000);
  EXPECT_EQ(chunk.data.size(), 4096u);
  EXPECT_EQ(chunk.total_size, 10000u);
  EXPECT_EQ(std::string(chunk.data.begin(), chunk.data.end()), bytes.substr(1000, 4096));
  chunk = reader.read("c/f.mp4", 9990, 100);
  EXPECT_EQ(std::string(chunk.data.begin(), chunk.data.end()), bytes.substr(9990));
  EXPECT_TRUE(reader.read("c/f.mp4", 10000, 100).data.empty());
  try {
    reader.read("c/f.mp4", 10001, 1);
    FAIL() << "read past the end";
  } catch (const ChunkError& e) {
    EXPECT_EQ(e.kind(), ChunkError::Kind::BAD_RANGE);
  }
}

TEST(ChunkReader, RefusesAFileChangedSinceItWasCatalogued) {
  TempDir dir("changed");
  writeFile(dir.path() / "c" / "f.mp4", randomBytes(5000, 12));
  const auto stamp = stampOf(dir.path() / "c" / "f.mp4");
  ASSERT_TRUE(stamp);
  ChunkReader reader(dir.path(), 4096);
  EXPECT_EQ(reader.read("c/f.mp4", 0, 10, stamp).data.size(), 10u);
  fs::resize_file(dir.path() / "c" / "f.mp4", 100);
  try {
    reader.read("c/f.mp4", 0, 10, stamp);
    FAIL() << "served a truncated file";
  } catch (const ChunkError& e) {
    EXPECT_EQ(e.kind(), ChunkError::Kind::CHANGED);
    EXPECT_NE(std::string(e.what()).find("5000 -> 100"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace auv::transfer
