// The catalogue of a recordings root (no DDS): what is listed, hashed once, noticed when it
// changes after being catalogued, and how bad input is reported. (SHA-256 itself is tested with
// the transfer protocol, components/transfer/test.)
#include "auv/recorder/catalogue.h"

#include <gtest/gtest.h>

#include "auv/transfer/sha256.h"
#include "test_files.h"

namespace auv::recorder {
namespace {

namespace fs = std::filesystem;
using testing::randomBytes;
using testing::sidecarText;
using testing::TempDir;
using testing::writeFile;
using testing::writeRecording;

#define EXPECT_CONTAINS(text, part) \
  EXPECT_NE(std::string(text).find(part), std::string::npos) << "'" << (text) << "'"

TEST(Catalogue, KeepsChunkDigestsOnItsGridForTheCataloguedState) {
  TempDir dir("grid");
  const std::string path = writeRecording(dir.path(), "left", 1, 10000, 5, 12);
  const std::string bytes = testing::readFile(dir.path() / path);
  Catalogue catalogue({dir.path(), {".mp4"}, 4096});
  catalogue.scan();
  const auto served = catalogue.servedFile(path);
  ASSERT_TRUE(served);
  const FileStamp stamp = served->stamp;
  const auto digest = catalogue.chunkDigest(path, stamp, 4096, 4096);
  ASSERT_TRUE(digest);
  EXPECT_EQ(*digest, Sha256::of(bytes.data() + 4096, 4096));
  const auto last = catalogue.chunkDigest(path, stamp, 8192, 1808);  // the short last piece
  ASSERT_TRUE(last);
  EXPECT_EQ(*last, Sha256::of(bytes.data() + 8192, 1808));
  // Anything else is hashed by the caller: off the grid, another length, past the end,
  // another state of the file, the sidecar, an unknown file.
  EXPECT_FALSE(catalogue.chunkDigest(path, stamp, 100, 4096));
  EXPECT_FALSE(catalogue.chunkDigest(path, stamp, 0, 2048));
  EXPECT_FALSE(catalogue.chunkDigest(path, stamp, 8192, 4096));
  EXPECT_FALSE(catalogue.chunkDigest(path, stamp, 12288, 0));
  FileStamp other = stamp;
  other.mtime_ns += 1;
  EXPECT_FALSE(catalogue.chunkDigest(path, other, 0, 4096));
  EXPECT_FALSE(catalogue.chunkDigest(path + ".frames.csv", stamp, 0, 4096));
  EXPECT_FALSE(catalogue.chunkDigest("left/none.mp4", stamp, 0, 4096));
  // Not served once the chunk server reported a change; kept again after a clean rescan.
  catalogue.reportChanged(path, "changed since it was catalogued");
  EXPECT_FALSE(catalogue.chunkDigest(path, stamp, 0, 4096));
  catalogue.scan();
  EXPECT_TRUE(catalogue.chunkDigest(path, catalogue.servedFile(path)->stamp, 0, 4096));
  // No grid: no digests kept.
  Catalogue plain({dir.path(), {".mp4"}});
  plain.scan();
  EXPECT_FALSE(plain.chunkDigest(path, plain.servedFile(path)->stamp, 0, 4096));
}

TEST(Catalogue, MissingRootIsAnEmptyCatalogue) {
  TempDir dir("missing");
  Catalogue catalogue({dir.path() / "not_yet", {".mp4"}});
  EXPECT_FALSE(catalogue.walked());
  catalogue.scan();
  EXPECT_TRUE(catalogue.walked());
  EXPECT_TRUE(catalogue.list("", true).empty());
}

TEST(Catalogue, ListsClosedRecordingsWithDigestsAndFrameTimes) {
  TempDir dir("closed");
  const std::string left = writeRecording(dir.path(), "left", 1, 100000, 25, 1);
  const std::string right = writeRecording(dir.path(), "right", 1, 5000, 3, 2);
  writeFile(dir.path() / "left" / "notes.txt", "not a recording");
  Catalogue catalogue({dir.path(), {".mp4"}});
  const ScanReport report = catalogue.scan();
  EXPECT_TRUE(report.modified);
  EXPECT_EQ(report.hashed, 4u);  // two recordings, two sidecars
  const auto all = catalogue.list("", false);
  ASSERT_EQ(all.size(), 2u);
  const Recording& r = all[0];
  EXPECT_EQ(r.camera_id, "left");
  EXPECT_EQ(r.file_path, left);
  EXPECT_TRUE(r.complete);
  EXPECT_TRUE(r.problem.empty()) << r.problem;
  EXPECT_EQ(r.size_bytes, 100000u);
  EXPECT_EQ(r.sha256, transfer::sha256OfFile(dir.path() / left));
  EXPECT_EQ(r.sidecar_file, left + ".frames.csv");
  EXPECT_EQ(r.sidecar_sha256, transfer::sha256OfFile(dir.path() / r.sidecar_file));
  EXPECT_EQ(r.sidecar_size_bytes, fs::file_size(dir.path() / r.sidecar_file));
  EXPECT_EQ(r.frame_count, 25u);
  EXPECT_DOUBLE_EQ(r.start_time_s, 10.0);
  EXPECT_NEAR(r.end_time_s, 12.4, 1e-6);
  EXPECT_EQ(all[1].file_path, right);
  EXPECT_EQ(catalogue.list("right", false).size(), 1u);
  EXPECT_TRUE(catalogue.hasCamera("left"));
  EXPECT_FALSE(catalogue.hasCamera("down"));
  EXPECT_EQ(catalogue.pendingFiles(), 0u);
}

TEST(Catalogue, IncompleteFilesAreListedOnRequestAndCompletedWhenRenamed) {
  TempDir dir("incomplete");
  const fs::path camera = dir.path() / "forward";
  writeFile(camera / "forward_0001.incomplete.mp4", randomBytes(3000, 3));
  // The writer is half-way through line 3: only whole lines count.
  writeFile(camera / "forward_0001.mp4.frames.csv.incomplete", sidecarText(2) + "2,100.2");
  Catalogue catalogue({dir.path(), {".mp4"}});
  catalogue.scan();
  EXPECT_TRUE(catalogue.list("", false).empty());
  auto open = catalogue.list("", true);
  ASSERT_EQ(open.size(), 1u);
  EXPECT_EQ(open[0].file_path, "forward/forward_0001.mp4");  // the final name is the key
  EXPECT_FALSE(open[0].complete);
  EXPECT_TRUE(open[0].sha256.empty());
  EXPECT_EQ(open[0].frame_count, 2u);
  EXPECT_EQ(open[0].size_bytes, 3000u);
  EXPECT_FALSE(catalogue.servedFile("forward/forward_0001.mp4"));

  // Closed as the simulator does: sidecar first, then the video.
  fs::rename(camera / "forward_0001.mp4.frames.csv.incomplete",
             camera / "forward_0001.mp4.frames.csv");
  writeFile(camera / "forward_0001.mp4.frames.csv", sidecarText(3));
  catalogue.scan();
  EXPECT_TRUE(catalogue.list("", false).empty()) << "video still open";
  fs::rename(camera / "forward_0001.incomplete.mp4", camera / "forward_0001.mp4");
  catalogue.scan();
  auto closed = catalogue.list("", false);
  ASSERT_EQ(closed.size(), 1u);
  EXPECT_TRUE(closed[0].complete);
  EXPECT_EQ(closed[0].frame_count, 3u);
  EXPECT_EQ(closed[0].sha256, transfer::sha256OfFile(camera / "forward_0001.mp4"));
  const auto served = catalogue.servedFile("forward/forward_0001.mp4.frames.csv");
  ASSERT_TRUE(served);
  EXPECT_EQ(served->relative_path, "forward/forward_0001.mp4.frames.csv");
}

TEST(Catalogue, RecordingClosedSinceTheLastScanIsPendingBeforeTheNextScan) {
  TempDir dir("pending_now");
  const fs::path camera = dir.path() / "forward";
  writeFile(camera / "forward_0001.incomplete.mp4", randomBytes(3000, 5));
  writeRecording(dir.path(), "left", 1, 2000, 2, 6);
  Catalogue catalogue({dir.path(), {".mp4"}});
  catalogue.scan();
  EXPECT_EQ(catalogue.pendingNow(), 0u) << "open files are not pending, hashed ones neither";

  // The writer closes its file and a new recording appears: the catalogue has not scanned yet,
  // but it knows it is behind the disk (a pull asking now must wait, not finish).
  fs::rename(camera / "forward_0001.incomplete.mp4", camera / "forward_0001.mp4");
  writeRecording(dir.path(), "left", 2, 1000, 2, 7);
  EXPECT_EQ(catalogue.pendingFiles(), 0u);
  EXPECT_EQ(catalogue.pendingNow(), 2u);
  catalogue.scan();
  EXPECT_EQ(catalogue.pendingNow(), 0u);
  EXPECT_EQ(catalogue.list("", false).size(), 3u);
}

TEST(Catalogue, HashesEachFileOnceAndAgainOnlyWhenSizeOrTimeChange) {
  TempDir dir("once");
  const std::string path = writeRecording(dir.path(), "left", 1, 20000, 5, 4);
  Catalogue catalogue({dir.path(), {".mp4"}});
  EXPECT_EQ(catalogue.scan().hashed, 2u);
  const uint64_t generation = catalogue.generation();
  const ScanReport again = catalogue.scan();
  EXPECT_EQ(again.hashed, 0u);
  EXPECT_FALSE(again.modified);
  EXPECT_EQ(catalogue.generation(), generation);

  // Touched, same bytes: hashed again, still complete, nothing to report.
  fs::last_write_time(dir.path() / path,
                      fs::last_write_time(dir.path() / path) + std::chrono::seconds(5));
  const ScanReport touched = catalogue.scan();
  EXPECT_EQ(touched.hashed, 2u);
  const auto list = catalogue.list("", false);
  ASSERT_EQ(list.size(), 1u);
  EXPECT_TRUE(list[0].complete);
  EXPECT_TRUE(list[0].problem.empty()) << list[0].problem;
}

TEST(Catalogue, FileTruncatedAfterCataloguingIsReportedAndNotServed) {
  TempDir dir("truncated");
  const std::string path = writeRecording(dir.path(), "left", 1, 50000, 5, 5);
  Catalogue catalogue({dir.path(), {".mp4"}});
  catalogue.scan();
  ASSERT_TRUE(catalogue.servedFile(path));
  fs::resize_file(dir.path() / path, 20000);
  const ScanReport report = catalogue.scan();
  EXPECT_TRUE(report.modified);
  ASSERT_EQ(report.messages.size(), 1u);
  EXPECT_CONTAINS(report.messages[0], path);
  EXPECT_CONTAINS(report.messages[0], "50000 -> 20000");
  EXPECT_TRUE(catalogue.list("", false).empty());
  const auto all = catalogue.list("", true);
  ASSERT_EQ(all.size(), 1u);
  EXPECT_FALSE(all[0].complete);
  EXPECT_TRUE(all[0].sha256.empty());
  EXPECT_CONTAINS(all[0].problem, "changed after it was catalogued complete");
  EXPECT_FALSE(catalogue.servedFile(path));
  EXPECT_FALSE(catalogue.servedFile(path + ".frames.csv"));
  // Still flagged at the next scan (it is not the file that was catalogued).
  EXPECT_FALSE(catalogue.scan().modified);
  EXPECT_FALSE(catalogue.list("", true)[0].complete);
}

TEST(Catalogue, ChangeReportedByTheChunkServerIsRecheckedByTheNextScan) {
  TempDir dir("reported");
  const std::string path = writeRecording(dir.path(), "left", 1, 1000, 2, 6);
  Catalogue catalogue({dir.path(), {".mp4"}});
  catalogue.scan();
  EXPECT_FALSE(catalogue.changedProblem(path));
  catalogue.reportChanged(path, "changed since it was catalogued");
  EXPECT_FALSE(catalogue.servedFile(path));
  EXPECT_EQ(catalogue.changedProblem(path), "changed since it was catalogued");
  EXPECT_EQ(catalogue.changedProblem(path + ".frames.csv"), "changed since it was catalogued");
  catalogue.scan();  // same bytes after all: complete again
  ASSERT_TRUE(catalogue.servedFile(path));
  EXPECT_FALSE(catalogue.changedProblem(path));
  EXPECT_TRUE(catalogue.list("", false)[0].problem.empty());
}

TEST(Catalogue, MalformedSidecarIsNamedAndTheVideoStillServed) {
  TempDir dir("sidecar");
  const std::string path = writeRecording(dir.path(), "left", 1, 1000, 2, 7);
  writeFile(dir.path() / (path + ".frames.csv"),
            "frame,camera_time_s,sim_time_s\n0,1.0,0\n1,abc,0.1\n");
  Catalogue catalogue({dir.path(), {".mp4"}});
  catalogue.scan();
  const auto list = catalogue.list("", false);
  ASSERT_EQ(list.size(), 1u);
  EXPECT_TRUE(list[0].complete);
  EXPECT_CONTAINS(list[0].problem, "left_0001.mp4.frames.csv line 3");
  EXPECT_CONTAINS(list[0].problem, "'abc'");
  EXPECT_EQ(list[0].frame_count, 0u);
}

TEST(Catalogue, RemovedFilesLeaveAndSymlinksAreNotFollowed) {
  TempDir dir("removed");
  TempDir outside("outside");
  const std::string path = writeRecording(dir.path(), "left", 1, 1000, 2, 8);
  writeRecording(outside.path(), "secret", 1, 1000, 2, 9);
  fs::create_directory_symlink(outside.path() / "secret", dir.path() / "secret");
  fs::create_symlink(outside.path() / "secret" / "secret_0001.mp4",
                     dir.path() / "left" / "left_0002.mp4");
  Catalogue catalogue({dir.path(), {".mp4"}});
  catalogue.scan();
  ASSERT_EQ(catalogue.list("", true).size(), 1u);
  fs::remove(dir.path() / path);
  const ScanReport report = catalogue.scan();
  EXPECT_TRUE(report.modified);
  EXPECT_TRUE(catalogue.list("", true).empty());
}

TEST(Catalogue, OptionsNameTheBadField) {
  try {
    Catalogue catalogue({"/tmp", {"mp4"}});
    FAIL() << "accepted an extension without a dot";
  } catch (const std::invalid_argument& e) {
    EXPECT_CONTAINS(e.what(), "extensions");
  }
  EXPECT_THROW(Catalogue({"", {".mp4"}}), std::invalid_argument);
}

}  // namespace
}  // namespace auv::recorder
