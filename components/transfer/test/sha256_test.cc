// The protocol's digests: SHA-256 through OpenSSL EVP, as lowercase hex; a file's digest and
// its chunks' digests in one read.
#include "auv/transfer/sha256.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "auv/transfer/testing/temp_files.h"

namespace auv::transfer {
namespace {

using testing::randomBytes;
using testing::TempDir;
using testing::writeFile;

#define EXPECT_CONTAINS(text, part) \
  EXPECT_NE(std::string(text).find(part), std::string::npos) << "'" << (text) << "'"

TEST(Sha256, KnownVectors) {
  EXPECT_EQ(Sha256::of("abc", 3),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(Sha256::of("", 0), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  Sha256 incremental;
  incremental.update("a", 1);
  incremental.update("bc", 2);
  EXPECT_EQ(incremental.hexDigest(), Sha256::of("abc", 3));
  EXPECT_TRUE(isSha256Hex(Sha256::of("x", 1)));
  EXPECT_FALSE(isSha256Hex("ABC"));
}

TEST(Sha256, FileAndChunkDigestsInOneRead) {
  TempDir dir("chunks");
  const std::string bytes = randomBytes(10000, 11);
  writeFile(dir.path() / "f.bin", bytes);
  const FileDigests digests = sha256OfFileAndChunks(dir.path() / "f.bin", 4096);
  EXPECT_EQ(digests.sha256, Sha256::of(bytes.data(), bytes.size()));
  ASSERT_EQ(digests.chunks.size(), 3u);  // 4096 + 4096 + 1808
  for (size_t i = 0; i < 3; ++i) {
    const size_t begin = 4096 * i, length = std::min<size_t>(4096, bytes.size() - begin);
    EXPECT_EQ(Sha256::toHex(digests.chunks[i]), Sha256::of(bytes.data() + begin, length)) << i;
  }
  // A whole number of pieces, a grid larger than the read buffer, an empty file.
  EXPECT_EQ(sha256OfFileAndChunks(dir.path() / "f.bin", 2500).chunks.size(), 4u);
  const FileDigests one = sha256OfFileAndChunks(dir.path() / "f.bin", 4u << 20);
  ASSERT_EQ(one.chunks.size(), 1u);
  EXPECT_EQ(Sha256::toHex(one.chunks[0]), digests.sha256);
  writeFile(dir.path() / "empty.bin", "");
  const FileDigests empty = sha256OfFileAndChunks(dir.path() / "empty.bin", 4096);
  EXPECT_EQ(empty.sha256, Sha256::of("", 0));
  EXPECT_TRUE(empty.chunks.empty());
  EXPECT_THROW(sha256OfFileAndChunks(dir.path() / "f.bin", 0), std::invalid_argument);
  try {
    sha256OfFileAndChunks(dir.path() / "missing.bin", 4096);
    ADD_FAILURE() << "no error for a missing file";
  } catch (const std::runtime_error& e) {
    EXPECT_CONTAINS(e.what(), "missing.bin");
  }
}

}  // namespace
}  // namespace auv::transfer
