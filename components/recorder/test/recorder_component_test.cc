// The recorder component on real DDS, with the client on the other vendor (Fast DDS server <->
// Cyclone client and the reverse): the catalogue, chunks that reassemble to the catalogued
// SHA-256, the per-chunk digest, paths outside the root refused, a file truncated after it was
// catalogued refused (REJECTED) and reported on the latched feed, names per vehicle. Each test
// on its own domain id (130-133, test/README.md).
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "auv/interfaces/executor.h"
#include "auv/recorder/components/recorder_component.h"
#include "auv/transfer/names.h"
#include "auv/transfer/sha256.h"
#include "test_files.h"

namespace auv::recorder {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using interfaces::CallStatus;
using interfaces::Node;
using interfaces::nodeOptions;
using interfaces::Vendor;
using testing::TempDir;
using testing::writeRecording;

#define EXPECT_CONTAINS(text, part) \
  EXPECT_NE(std::string(text).find(part), std::string::npos) << "'" << (text) << "'"

using ListClient = interfaces::Client<msg::RecordingCatalogueRequest, msg::RecordingCatalogueReply>;
using FetchClient = interfaces::Client<msg::FileChunkRequest, msg::FileChunkReply>;

/// The recorder in its own node and executor thread; the shore's node on another vendor.
class Harness {
 public:
  Harness(Vendor recorder_vendor, Vendor shore_vendor, int domain, const fs::path& root,
          const std::string& vehicle = "auv")
      : recorder_node_("recorder",
                       nodeOptions(recorder_vendor, domain,
                                   {"root:=" + root.string(), "vehicle_name:=" + vehicle,
                                    "scan_period:=0.2", "max_chunk_bytes:=65536"})),
        shore_("shore", nodeOptions(shore_vendor, domain)) {
    recorder.configure(recorder_node_);
    list = shore_.createClient<msg::RecordingCatalogueRequest, msg::RecordingCatalogueReply>(
        transfer::listRecordingsService(vehicle), interfaces::bulkTransferQos());
    fetch = shore_.createClient<msg::FileChunkRequest, msg::FileChunkReply>(
        transfer::fetchChunkService(vehicle), interfaces::bulkTransferQos());
    feed = shore_.createSubscription<msg::RecordingInfo>(
        transfer::recordingsTopic(vehicle), interfaces::latchedStateQos(),
        std::function<void(const msg::RecordingInfo&)>([this](const msg::RecordingInfo& info) {
          std::lock_guard<std::mutex> lock(feed_mutex_);
          feed_samples_.push_back(info);
        }),
        interfaces::SubscriptionOptions{interfaces::CallbackThread::MIDDLEWARE});
    executor_.add(recorder_node_);
    recorder.scanNow();  // the first catalogue is there before the first request
    recorder.activate();
    spinner_ = std::thread([this] { executor_.spin(); });
  }
  ~Harness() {
    executor_.shutdown();
    spinner_.join();
    recorder.deactivate();
    recorder.cleanup();
  }

  msg::RecordingCatalogueReply listAll(const std::string& camera = "", bool incomplete = false) {
    msg::RecordingCatalogueRequest request;
    request.camera_id(camera);
    request.include_incomplete(incomplete);
    msg::RecordingCatalogueReply reply;
    EXPECT_EQ(list->call(request, &reply, 20s), CallStatus::OK);
    return reply;
  }
  msg::FileChunkReply fetchChunk(const std::string& path, uint64_t offset, uint32_t length) {
    msg::FileChunkRequest request;
    request.file_path(path);
    request.offset(offset);
    request.length(length);
    msg::FileChunkReply reply;
    EXPECT_EQ(fetch->call(request, &reply, 20s), CallStatus::OK);
    return reply;
  }
  /// The whole file by chunks, each checked against its digest.
  std::string fetchAll(const std::string& path, uint32_t chunk) {
    std::string bytes;
    for (;;) {
      const auto reply = fetchChunk(path, bytes.size(), chunk);
      EXPECT_EQ(reply.status().code(), msg::REPLY_CODE_OK) << reply.status().error_text();
      if (reply.status().code() != msg::REPLY_CODE_OK) return bytes;
      EXPECT_EQ(reply.data_sha256(), Sha256::of(reply.data().data(), reply.data().size()));
      EXPECT_LE(reply.data().size(), 65536u);
      bytes.append(reply.data().begin(), reply.data().end());
      if (reply.eof()) return bytes;
      if (reply.data().empty()) {
        ADD_FAILURE() << "empty chunk before eof";
        return bytes;
      }
    }
  }
  std::vector<msg::RecordingInfo> feedSamples() {
    std::lock_guard<std::mutex> lock(feed_mutex_);
    return feed_samples_;
  }

  RecorderComponent recorder;
  std::shared_ptr<ListClient> list;
  std::shared_ptr<FetchClient> fetch;
  std::shared_ptr<interfaces::Subscription<msg::RecordingInfo>> feed;

 private:
  Node recorder_node_;
  Node shore_;
  interfaces::Executor executor_;
  std::thread spinner_;
  std::mutex feed_mutex_;
  std::vector<msg::RecordingInfo> feed_samples_;
};

void catalogueAndChunksAcrossVendors(Vendor recorder_vendor, Vendor shore_vendor, int domain) {
  TempDir dir("cross");
  const std::string left = writeRecording(dir.path(), "left", 1, 300000, 40, 21);
  const std::string right = writeRecording(dir.path(), "right", 1, 1000, 4, 22);
  Harness h(recorder_vendor, shore_vendor, domain, dir.path());
  const auto reply = h.listAll();
  ASSERT_EQ(reply.status().code(), msg::REPLY_CODE_OK) << reply.status().error_text();
  EXPECT_EQ(reply.pending_files(), 0u);
  EXPECT_EQ(reply.max_chunk_bytes(), 65536u);
  ASSERT_EQ(reply.recordings().size(), 2u);
  const msg::RecordingInfo& info = reply.recordings()[0];
  EXPECT_EQ(info.camera_id(), "left");
  EXPECT_EQ(info.file_path(), left);
  EXPECT_TRUE(info.complete());
  EXPECT_EQ(info.size_bytes(), 300000u);
  EXPECT_EQ(info.frame_count(), 40u);
  EXPECT_EQ(info.start_time().sec(), 10);
  EXPECT_EQ(info.sha256(), transfer::sha256OfFile(dir.path() / left));
  EXPECT_EQ(reply.recordings()[1].file_path(), right);

  // Asking for more than the cap gets the cap: the file arrives in 5 chunks.
  const std::string bytes = h.fetchAll(left, 1 << 20);
  EXPECT_EQ(bytes.size(), 300000u);
  EXPECT_EQ(Sha256::of(bytes.data(), bytes.size()), info.sha256());
  const std::string sidecar = h.fetchAll(info.sidecar_file(), 4096);
  EXPECT_EQ(Sha256::of(sidecar.data(), sidecar.size()), info.sidecar_sha256());

  // Filtered by camera; an unknown camera is NOT_FOUND.
  EXPECT_EQ(h.listAll("right").recordings().size(), 1u);
  const auto unknown = h.listAll("down");
  EXPECT_EQ(unknown.status().code(), msg::REPLY_CODE_NOT_FOUND);
  EXPECT_CONTAINS(unknown.status().error_text(), "'down'");
}

TEST(RecorderComponent, CatalogueAndChunksFastddsServerCycloneClient) {
  catalogueAndChunksAcrossVendors(Vendor::FASTDDS, Vendor::CYCLONEDDS, 130);
}

TEST(RecorderComponent, CatalogueAndChunksCycloneServerFastddsClient) {
  catalogueAndChunksAcrossVendors(Vendor::CYCLONEDDS, Vendor::FASTDDS, 131);
}

TEST(RecorderComponent, RefusesPathsOutsideTheRootAndUncataloguedFiles) {
  TempDir dir("refuse");
  TempDir outside("outside");
  writeRecording(dir.path(), "left", 1, 1000, 2, 23);
  testing::writeFile(dir.path() / "left" / "notes.txt", "not served");
  testing::writeFile(outside.path() / "secret.mp4", "secret");
  fs::create_symlink(outside.path() / "secret.mp4", dir.path() / "left" / "left_0009.mp4");
  Harness h(Vendor::CYCLONEDDS, Vendor::FASTDDS, 132, dir.path());
  for (const std::string path : {"../secret.mp4", "/etc/passwd", "left/../../x", "left//x"}) {
    const auto reply = h.fetchChunk(path, 0, 100);
    EXPECT_EQ(reply.status().code(), msg::REPLY_CODE_INVALID_ARGUMENT) << path;
    EXPECT_CONTAINS(reply.status().error_text(), "file_path '" + path + "'");
    EXPECT_TRUE(reply.data().empty());
  }
  for (const std::string path : {"left/notes.txt", "left/left_0009.mp4", "left/none.mp4"}) {
    const auto reply = h.fetchChunk(path, 0, 100);
    EXPECT_EQ(reply.status().code(), msg::REPLY_CODE_NOT_FOUND) << path;
    EXPECT_TRUE(reply.data().empty());
  }
  const auto past_end = h.fetchChunk("left/left_0001.mp4", 5000, 100);
  EXPECT_EQ(past_end.status().code(), msg::REPLY_CODE_INVALID_ARGUMENT);
}

TEST(RecorderComponent, TruncatedFileIsRejectedAndReportedOnTheFeed) {
  TempDir dir("truncate");
  const std::string path = writeRecording(dir.path(), "left", 1, 200000, 10, 24);
  Harness h(Vendor::FASTDDS, Vendor::CYCLONEDDS, 133, dir.path(), "sparus2");
  ASSERT_EQ(h.fetchChunk(path, 0, 1000).status().code(), msg::REPLY_CODE_OK);
  // The feed's latched sample (complete) arrives first.
  for (int i = 0; i < 400 && h.feedSamples().empty(); ++i) std::this_thread::sleep_for(50ms);
  ASSERT_EQ(h.feedSamples().size(), 1u);
  fs::resize_file(dir.path() / path, 100000);
  // The next chunk notices at once (before any rescan).
  const auto reply = h.fetchChunk(path, 1000, 1000);
  EXPECT_EQ(reply.status().code(), msg::REPLY_CODE_REJECTED);
  EXPECT_CONTAINS(reply.status().error_text(), "200000 -> 100000");
  EXPECT_TRUE(reply.data().empty());
  // Chunks asked for after that (a puller keeps several in flight) are refused the same way,
  // not answered "not found", which a puller would retry until its timeout.
  const auto later = h.fetchChunk(path, 2000, 1000);
  EXPECT_EQ(later.status().code(), msg::REPLY_CODE_REJECTED);
  EXPECT_CONTAINS(later.status().error_text(), "changed");
  // The catalogue no longer lists it as complete, and says why.
  EXPECT_TRUE(h.listAll().recordings().empty());
  msg::RecordingInfo reported;
  for (int i = 0; i < 200 && reported.problem().empty(); ++i) {
    const auto reply_all = h.listAll("", true);  // kept: recordings() refers into it
    for (const auto& info : reply_all.recordings()) {
      if (info.file_path() == path) reported = info;
    }
    if (reported.problem().find("changed after") == std::string::npos) {
      reported = {};
      std::this_thread::sleep_for(50ms);  // the rescan the chunk server asked for
    }
  }
  EXPECT_FALSE(reported.complete());
  EXPECT_CONTAINS(reported.problem(), "changed after it was catalogued complete");
  // The latched feed carried the complete file first, then the problem.
  std::vector<msg::RecordingInfo> feed;
  for (int i = 0; i < 200; ++i) {
    feed = h.feedSamples();
    if (!feed.empty() && !feed.back().problem().empty()) break;
    std::this_thread::sleep_for(50ms);
  }
  ASSERT_GE(feed.size(), 2u);
  EXPECT_TRUE(feed.front().complete());
  EXPECT_FALSE(feed.back().complete());
  EXPECT_CONTAINS(feed.back().problem(), "changed");
}

TEST(RecorderComponent, BadParametersAreNamed) {
  Node node("recorder", nodeOptions(Vendor::CYCLONEDDS, 133, {"root:=/tmp", "vehicle_name:=9x"}));
  RecorderComponent recorder;
  try {
    recorder.configure(node);
    FAIL() << "accepted vehicle_name 9x";
  } catch (const std::exception& e) {
    EXPECT_CONTAINS(e.what(), "vehicle_name");
  }
  Node empty_root("recorder", nodeOptions(Vendor::CYCLONEDDS, 133));
  RecorderComponent no_root;
  EXPECT_THROW(no_root.configure(empty_root), std::invalid_argument);
}

}  // namespace
}  // namespace auv::recorder
