// `auv recon pull`'s puller against the real recorder component on real DDS, the two on
// different vendors: byte-identical verified files and a manifest; a resume fetches no chunk
// already on disk; a chunk corrupted on the way is detected and fetched again; a file truncated
// on the vehicle is reported and never presented as complete; a vehicle that disappears gives
// a clear error; a recorder restarted mid-pull is picked up and the pull completes. Each test
// on its own domain id (134-139, test/README.md). A system test: the shore's package does not
// depend on the vehicle's component, this package depends on both.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <fstream>
#include <future>
#include <mutex>
#include <random>
#include <set>
#include <thread>

#include "auv/interfaces/executor.h"
#include "auv/recon/transfer/manifest.h"
#include "auv/recon/transfer/partial_file.h"
#include "auv/recon/transfer/puller.h"
#include "auv/recorder/components/recorder_component.h"
#include "auv/transfer/names.h"
#include "auv/transfer/sha256.h"

namespace auv::recon::transfer {
namespace {

namespace fs = std::filesystem;
using interfaces::Node;
using interfaces::nodeOptions;
using interfaces::Vendor;

#define EXPECT_CONTAINS(text, part) \
  EXPECT_NE(std::string(text).find(part), std::string::npos) << "'" << (text) << "'"

class TempDir {
 public:
  explicit TempDir(const std::string& tag) {
    path_ = fs::temp_directory_path() /
            ("auv_pull_" + tag + "_" + std::to_string(::getpid()) + "_" +
             std::to_string(std::chrono::steady_clock::now().time_since_epoch().count()));
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

std::string readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void writeFile(const fs::path& path, const std::string& content) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary | std::ios::trunc) << content;
}

/// A vehicle's recordings: `<camera>/<camera>_0001.mp4` of random bytes + sidecar, per camera.
std::vector<std::string> makeRecordings(const fs::path& root,
                                        const std::vector<std::pair<std::string, size_t>>& files) {
  std::vector<std::string> paths;
  uint32_t seed = 1;
  for (const auto& [camera, size] : files) {
    std::mt19937 generator(seed++);
    std::string bytes(size, '\0');
    for (auto& b : bytes) b = static_cast<char>(generator() & 0xFF);
    const std::string path = camera + "/" + camera + "_0001.mp4";
    writeFile(root / path, bytes);
    std::string sidecar = "frame,camera_time_s,sim_time_s\n";
    for (int i = 0; i < 30; ++i)
      sidecar += std::to_string(i) + "," + std::to_string(i / 10.0) + ",0\n";
    writeFile(root / (path + ".frames.csv"), sidecar);
    paths.push_back(path);
    paths.push_back(path + ".frames.csv");
  }
  return paths;
}

/// The recorder component in its own node and executor thread: one "vehicle process".
class Vehicle {
 public:
  Vehicle(Vendor vendor, int domain, const fs::path& root, double scan_period = 0.2,
          uint32_t max_chunk = 65536)
      : node_("recorder", nodeOptions(vendor, domain,
                                      {"root:=" + root.string(), "vehicle_name:=sparus",
                                       "scan_period:=" + std::to_string(scan_period),
                                       "max_chunk_bytes:=" + std::to_string(max_chunk)})) {
    recorder_.configure(node_);
    recorder_.setChunkObserver([this](const std::string& path, uint64_t offset, uint64_t bytes) {
      std::lock_guard<std::mutex> lock(mutex_);
      served_.push_back({path, offset, bytes});
    });
    recorder_.scanNow();
    recorder_.activate();
    executor_.add(node_);
    spinner_ = std::thread([this] { executor_.spin(); });
  }
  ~Vehicle() {
    executor_.shutdown();
    spinner_.join();
    recorder_.deactivate();
    recorder_.cleanup();
  }
  struct Served {
    std::string path;
    uint64_t offset, bytes;
  };
  std::vector<Served> served() {
    std::lock_guard<std::mutex> lock(mutex_);
    return served_;
  }

 private:
  Node node_;
  recorder::RecorderComponent recorder_;
  interfaces::Executor executor_;
  std::thread spinner_;
  std::mutex mutex_;
  std::vector<Served> served_;
};

PullOptions pullOptions(const fs::path& survey, double timeout_s = 30) {
  PullOptions options;
  options.vehicle = "sparus";
  options.survey = survey;
  options.timeout_s = timeout_s;
  options.in_flight = 4;
  options.chunk_bytes = 65536;
  options.progress_period_s = 0;  // a callback per chunk: the tests act at exact points
  return options;
}

void expectIdentical(const fs::path& root, const fs::path& survey,
                     const std::vector<std::string>& paths) {
  const Manifest manifest(survey / "recordings" / "manifest.json");
  for (const auto& path : paths) {
    const fs::path local = survey / "recordings" / path;
    ASSERT_TRUE(fs::exists(local)) << local;
    EXPECT_TRUE(readFile(local) == readFile(root / path)) << path << " differs";
    EXPECT_FALSE(fs::exists(PartialFile::partPath(local))) << path;
    EXPECT_FALSE(fs::exists(PartialFile::progressPath(local))) << path;
    if (path.size() > 4 && path.compare(path.size() - 4, 4, ".mp4") == 0) {
      const ManifestEntry* entry = manifest.find(path);
      ASSERT_NE(entry, nullptr) << path;
      EXPECT_EQ(entry->sha256, auv::transfer::sha256OfFile(root / path));
      EXPECT_EQ(entry->sidecar_sha256, auv::transfer::sha256OfFile(root / (path + ".frames.csv")));
      EXPECT_EQ(entry->frame_count, 30u);
    }
  }
}

/// The chunk indices (of `chunk_bytes`) of each file present on disk in the survey's partials.
std::map<std::string, std::set<uint64_t>> chunksOnDisk(const fs::path& survey,
                                                       const std::vector<std::string>& paths,
                                                       uint64_t* missing_bytes) {
  std::map<std::string, std::set<uint64_t>> present;
  *missing_bytes = 0;
  for (const auto& path : paths) {
    const fs::path local = survey / "recordings" / path;
    if (fs::exists(local)) continue;
    std::ifstream record(PartialFile::progressPath(local));
    if (!record) continue;
    std::string line, key;
    uint64_t size = 0, chunk_bytes = 0;
    while (std::getline(record, line)) {
      std::istringstream fields(line);
      fields >> key;
      if (key == "size") fields >> size;
      if (key == "chunk_bytes") fields >> chunk_bytes;
      uint64_t index = 0;
      if (key == "chunk" && (fields >> index)) present[path].insert(index * chunk_bytes);
    }
    uint64_t have = 0;
    for (uint64_t offset : present[path]) have += std::min<uint64_t>(chunk_bytes, size - offset);
    *missing_bytes += size - have;
  }
  return present;
}

TEST(Pull, ResumesWithoutFetchingChunksOnDiskFastddsVehicleCycloneShore) {
  TempDir root("root"), survey("survey");
  const auto paths = makeRecordings(root.path(), {{"left", 3000000}, {"right", 2000000}});
  Vehicle vehicle(Vendor::FASTDDS, 134, root.path());
  Node shore("shore", nodeOptions(Vendor::CYCLONEDDS, 134));
  {
    Puller puller(shore, pullOptions(survey.path()));
    puller.onProgress([&](const PullProgress& p) {
      if (p.bytes_total > 0 && p.bytes_done * 3 >= p.bytes_total) puller.stop();
    });
    EXPECT_EQ(puller.run(), PullResult::INTERRUPTED);
  }
  // Nothing is presented under a final name before it is complete and verified.
  uint64_t missing = 0;
  const auto present = chunksOnDisk(survey.path(), paths, &missing);
  ASSERT_FALSE(present.empty());
  for (const auto& path : paths) {
    if (fs::exists(survey.path() / "recordings" / path)) {
      EXPECT_EQ(readFile(survey.path() / "recordings" / path), readFile(root.path() / path));
    }
  }
  const size_t served_before = vehicle.served().size();
  Puller puller(shore, pullOptions(survey.path()));
  ASSERT_EQ(puller.run(), PullResult::COMPLETE);
  expectIdentical(root.path(), survey.path(), paths);
  const PullStats& stats = puller.stats();
  EXPECT_EQ(stats.bytes_missing, missing);
  EXPECT_GT(stats.chunks_reused, 0u);
  if (stats.requests_timed_out == 0) {
    EXPECT_EQ(stats.bytes_requested, missing);
  }
  // Server side: no chunk that was on disk was asked for again (late replies of the first run
  // may still be served after it stopped: those were for chunks not on disk).
  const auto served = vehicle.served();
  for (size_t i = served_before; i < served.size(); ++i) {
    auto it = present.find(served[i].path);
    if (it == present.end()) continue;
    EXPECT_EQ(it->second.count(served[i].offset), 0u)
        << served[i].path << " offset " << served[i].offset << " was on disk";
  }
}

TEST(Pull, CycloneVehicleFastddsShoreAndNothingAgainWhenComplete) {
  TempDir root("root"), survey("survey");
  const auto paths = makeRecordings(root.path(), {{"forward", 700000}, {"down", 100}});
  Vehicle vehicle(Vendor::CYCLONEDDS, 135, root.path());
  Node shore("shore", nodeOptions(Vendor::FASTDDS, 135));
  {
    Puller puller(shore, pullOptions(survey.path()));
    ASSERT_EQ(puller.run(), PullResult::COMPLETE);
    EXPECT_EQ(puller.stats().recordings_pulled, 2u);
    EXPECT_EQ(puller.stats().files_pulled, 4u);
  }
  expectIdentical(root.path(), survey.path(), paths);
  const size_t served = vehicle.served().size();
  Puller again(shore, pullOptions(survey.path()));
  ASSERT_EQ(again.run(), PullResult::COMPLETE);
  EXPECT_EQ(again.stats().recordings_present, 2u);
  EXPECT_EQ(again.stats().bytes_requested, 0u);
  EXPECT_EQ(vehicle.served().size(), served);
}

TEST(Pull, CorruptedChunkIsDetectedAndFetchedAgain) {
  // The vehicle side is the real catalogue and chunk reader behind a service that flips one
  // byte of the first reply for offset 131072 (after computing the digest): a corrupted link.
  TempDir root("root"), survey("survey");
  const auto paths = makeRecordings(root.path(), {{"left", 400000}});
  recorder::Catalogue catalogue({root.path(), {".mp4"}});
  catalogue.scan();
  auv::transfer::ChunkReader reader(root.path(), 65536);
  Node vehicle("recorder", nodeOptions(Vendor::CYCLONEDDS, 136));
  std::atomic<int> requests_at_offset{0};
  auto list = vehicle.createService<msg::RecordingCatalogueRequest, msg::RecordingCatalogueReply>(
      auv::transfer::listRecordingsService("sparus"),
      [&](const msg::RecordingCatalogueRequest&, msg::RecordingCatalogueReply& reply) {
        std::vector<msg::RecordingInfo> infos;
        for (const auto& r : catalogue.list("", true))
          infos.push_back(recorder::toRecordingInfo(r));
        reply.recordings(infos);
        reply.max_chunk_bytes(65536);
      },
      interfaces::bulkTransferQos());
  auto fetch = vehicle.createService<msg::FileChunkRequest, msg::FileChunkReply>(
      auv::transfer::fetchChunkService("sparus"),
      [&](const msg::FileChunkRequest& request, msg::FileChunkReply& reply) {
        auv::transfer::Chunk chunk =
            reader.read(request.file_path(), request.offset(), request.length());
        reply.file_path(request.file_path());
        reply.offset(request.offset());
        reply.total_size(chunk.total_size);
        reply.eof(request.offset() + chunk.data.size() == chunk.total_size);
        reply.data_sha256(auv::transfer::Sha256::of(chunk.data.data(), chunk.data.size()));
        if (request.file_path() == paths[0] && request.offset() == 131072 &&
            requests_at_offset++ == 0) {
          chunk.data[100] ^= 0x40;
        }
        reply.data(chunk.data);
      },
      interfaces::bulkTransferQos());
  interfaces::Executor executor;
  executor.add(vehicle);
  std::thread spinner([&] { executor.spin(); });
  Node shore("shore", nodeOptions(Vendor::FASTDDS, 136));
  Puller puller(shore, pullOptions(survey.path()));
  std::vector<std::string> messages;
  puller.onMessage([&](const std::string& m) { messages.push_back(m); });
  const PullResult result = puller.run();
  executor.shutdown();
  spinner.join();
  ASSERT_EQ(result, PullResult::COMPLETE);
  EXPECT_EQ(puller.stats().chunks_corrupted, 1u);
  EXPECT_EQ(requests_at_offset.load(), 2);
  expectIdentical(root.path(), survey.path(), paths);
  bool named = false;
  for (const auto& m : messages)
    named = named || m.find("offset 131072 arrived corrupted") != std::string::npos;
  EXPECT_TRUE(named);
}

TEST(Pull, FileTruncatedOnTheVehicleIsReportedAndNotPresentedAsComplete) {
  TempDir root("root"), survey("survey");
  const auto paths = makeRecordings(root.path(), {{"left", 500000}, {"right", 300000}});
  // Catalogued complete, then truncated before the pull; no periodic rescan meanwhile.
  Vehicle vehicle(Vendor::CYCLONEDDS, 137, root.path(), 3600.0);
  fs::resize_file(root.path() / paths[0], 200000);
  Node shore("shore", nodeOptions(Vendor::FASTDDS, 137));
  Puller puller(shore, pullOptions(survey.path()));
  EXPECT_EQ(puller.run(), PullResult::FAILED_FILES);
  ASSERT_EQ(puller.stats().problems.size(), 1u);
  EXPECT_CONTAINS(puller.stats().problems[0], paths[0]);
  EXPECT_CONTAINS(puller.stats().problems[0], "changed");
  EXPECT_FALSE(fs::exists(survey.path() / "recordings" / paths[0]));
  const Manifest manifest(survey.path() / "recordings" / "manifest.json");
  EXPECT_EQ(manifest.find(paths[0]), nullptr);
  expectIdentical(root.path(), survey.path(), {paths[2], paths[3]});
  // Pulled again: the vehicle's catalogue now says why, still not pulled.
  Puller again(shore, pullOptions(survey.path()));
  EXPECT_EQ(again.run(), PullResult::FAILED_FILES);
  ASSERT_EQ(again.stats().problems.size(), 1u);
  EXPECT_CONTAINS(again.stats().problems[0], "changed after it was catalogued complete");
  EXPECT_FALSE(fs::exists(survey.path() / "recordings" / paths[0]));
}

TEST(Pull, VehicleThatDisappearsGivesAClearErrorAfterTheTimeout) {
  TempDir root("root"), survey("survey");
  const auto paths = makeRecordings(root.path(), {{"left", 2000000}});
  Node shore("shore", nodeOptions(Vendor::FASTDDS, 138));
  {
    // No vehicle at all.
    Puller puller(shore, pullOptions(survey.path(), 1.0));
    EXPECT_EQ(puller.run(), PullResult::VEHICLE_LOST);
    EXPECT_CONTAINS(puller.stats().lost, "vehicle 'sparus' was not found within 1 s");
  }
  auto vehicle = std::make_unique<Vehicle>(Vendor::CYCLONEDDS, 138, root.path());
  Puller puller(shore, pullOptions(survey.path(), 2.0));
  bool stopped = false;
  puller.onProgress([&](const PullProgress& p) {
    // A third of the way, the vehicle goes away for good (the pull waits meanwhile).
    if (!stopped && p.bytes_total > 0 && p.bytes_done * 3 >= p.bytes_total) {
      stopped = true;
      vehicle.reset();
    }
  });
  EXPECT_EQ(puller.run(), PullResult::VEHICLE_LOST);
  EXPECT_TRUE(stopped);
  EXPECT_CONTAINS(puller.stats().lost, "vehicle 'sparus' stopped answering");
  EXPECT_FALSE(fs::exists(survey.path() / "recordings" / paths[0]));
  EXPECT_TRUE(fs::exists(PartialFile::partPath(survey.path() / "recordings" / paths[0])));
}

TEST(Pull, RecorderRestartedMidPullCompletes) {
  TempDir root("root"), survey("survey");
  const auto paths = makeRecordings(root.path(), {{"left", 3000000}, {"right", 1000000}});
  auto vehicle = std::make_unique<Vehicle>(Vendor::CYCLONEDDS, 139, root.path());
  Node shore("shore", nodeOptions(Vendor::FASTDDS, 139));
  Puller puller(shore, pullOptions(survey.path(), 60.0));
  std::atomic<bool> restart{false};
  std::promise<void> stopped;
  puller.onProgress([&](const PullProgress& p) {
    if (!restart && p.bytes_total > 0 && p.bytes_done * 3 >= p.bytes_total) {
      restart = true;
      vehicle.reset();  // the vehicle process stops mid-pull...
      stopped.set_value();
    }
  });
  std::thread restarter([&] {
    stopped.get_future().wait();
    // ...and a new recorder process serves the same files.
    vehicle = std::make_unique<Vehicle>(Vendor::CYCLONEDDS, 139, root.path());
  });
  const PullResult result = puller.run();
  restarter.join();
  ASSERT_EQ(result, PullResult::COMPLETE) << puller.stats().lost;
  EXPECT_TRUE(restart);
  expectIdentical(root.path(), survey.path(), paths);
}

}  // namespace
}  // namespace auv::recon::transfer
