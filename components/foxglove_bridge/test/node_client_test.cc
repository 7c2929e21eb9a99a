// The bridge against Foxglove's own client (js/README.md): test/js/bridge_check.mjs connects
// with @foxglove/ws-protocol, receives the advertisements, subscribes, and decodes a sample of
// EVERY type of the message set, published with a value in every field from Fast DDS and from
// Cyclone DDS, with @foxglove/omgidl-serialization and the schema the bridge sent; the values
// must be those published. Then malformed messages each get an error status, a client that
// stops reading loses best-effort samples while the publisher and a reading client go on, and
// the bridge still accepts a connection. Skipped without node or js/node_modules. Domain 159.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <map>
#include <sstream>

#include "bridge_harness.h"
#include "sample_filler.h"
#include "serialized_test_util.h"

namespace auv::foxglove_bridge {
namespace {

using namespace std::chrono_literals;
using interfaces::Vendor;
namespace fs = std::filesystem;
const fs::path kRepository = AUV_SOURCE_ROOT;

std::string run(const std::string& command, int* status) {
  FILE* pipe = ::popen(command.c_str(), "r");
  std::string output;
  char buffer[65536];
  for (size_t n; (n = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0;) output.append(buffer, n);
  *status = ::pclose(pipe);
  return output;
}

TEST(FoxgloveBridgeNode, FoxgloveClientDecodesEveryTypeFromBothVendors) {
  if (std::system("node --version > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "node not found: scripts/install-deps.sh installs it";
  if (!fs::exists(kRepository / "js/node_modules/@foxglove/ws-protocol"))
    GTEST_SKIP() << (kRepository / "js/node_modules").string()
                 << " is missing: scripts/install-deps.sh runs npm ci there";
  const int domain = 159;
  test::BridgeHarness bridge(Vendor::CYCLONEDDS, domain, {"send_buffer_limit:=300000"});
  struct Published {
    const msg::TypeSupport* type;
    std::shared_ptr<void> sample;
    std::unique_ptr<interfaces::DataWriter> writer;
  };
  std::map<std::string, Published> published;
  std::vector<std::unique_ptr<interfaces::Participant>> participants;
  for (Vendor vendor : {Vendor::FASTDDS, Vendor::CYCLONEDDS}) {
    participants.push_back(interfaces::createParticipant(vendor, {domain, "publisher"}));
    for (const msg::TypeSupport& type : msg::allTypes()) {
      const std::string topic =
          "/fox/" + interfaces::toString(vendor) + "/" + type.name.substr(type.name.rfind(':') + 1);
      Published p{&type, interfaces::test::SampleFiller(type).sample(), nullptr};
      // Transient local: the bridge's reader, made when the client subscribes, gets it.
      p.writer = participants.back()->createWriter(topic, type, interfaces::latchedStateQos());
      p.writer->write(p.sample.get());
      published[topic] = std::move(p);
    }
  }
  // Best-effort frames of 200 kB at 50 Hz for the slow client.
  const auto& image_type = interfaces::typeSupportByName("CompressedImage");
  auto image = std::static_pointer_cast<msg::CompressedImage>(image_type.create_sample());
  image->data(std::vector<uint8_t>(200000, 1));
  auto stream = participants[0]->createWriter("/stream", image_type, interfaces::sensorDataQos());
  std::atomic<bool> streaming{true};
  std::atomic<int64_t> slowest_write_us{0};
  std::thread streamer([&] {
    while (streaming) {
      const auto start = std::chrono::steady_clock::now();
      stream->write(image.get());
      const int64_t us = std::chrono::duration_cast<std::chrono::microseconds>(
                             std::chrono::steady_clock::now() - start)
                             .count();
      if (us > slowest_write_us) slowest_write_us = us;
      std::this_thread::sleep_for(20ms);
    }
  });
  int status = 0;
  const std::string output = run(
      "node '" + (kRepository / "components/foxglove_bridge/test/js/bridge_check.mjs").string() +
          "' '" + bridge.uri() + "' /fox/ " + std::to_string(published.size()) +
          " /stream 120000 2>&1",
      &status);
  streaming = false;
  streamer.join();
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << output;
  std::istringstream lines(output);
  std::map<std::string, std::string> samples;
  int statuses = 0;
  long fast_frames = -1, slow_frames = -1;
  bool alive = false;
  for (std::string line; std::getline(lines, line);) {
    std::istringstream words(line);
    std::string kind, topic;
    words >> kind;
    if (kind == "sample") {
      words >> topic;
      std::getline(words, samples[topic]);
    } else if (kind == "status") {
      int level = -1;
      words >> level;
      EXPECT_EQ(level, 2) << line;
      ++statuses;
    } else if (kind == "slow") {
      words >> fast_frames >> slow_frames;
    } else if (kind == "alive") {
      alive = true;
    }
  }
  ASSERT_EQ(samples.size(), published.size()) << output;
  for (const auto& [topic, p] : published) {
    SCOPED_TRACE(topic);
    auto decoded = p.type->create_sample();
    try {
      p.type->from_yaml(YAML::Load(samples.at(topic)), decoded.get());
    } catch (const std::exception& e) {
      ADD_FAILURE() << "Foxglove's decode does not fit the type: " << e.what() << "\n"
                    << samples.at(topic);
      continue;
    }
    EXPECT_EQ(YAML::Dump(p.type->to_yaml(decoded.get())),
              YAML::Dump(p.type->to_yaml(p.sample.get())));
  }
  EXPECT_EQ(statuses, 7) << output;
  EXPECT_GT(fast_frames, 50) << output;           // ~150 streamed in its 3 s
  EXPECT_LT(slow_frames, fast_frames) << output;  // the paused client got fewer
  EXPECT_GT(bridge.component().server().droppedMessages(), 0u);
  EXPECT_LT(slowest_write_us, 100000);  // the publisher never waited for a client
  EXPECT_TRUE(alive) << output;
  std::printf(
      "types %zu x 2 vendors decoded; fast client %ld frames, paused client %ld, dropped %lu, "
      "slowest write %ld us\n",
      published.size() / 2, fast_frames, slow_frames,
      static_cast<unsigned long>(bridge.component().server().droppedMessages()),
      static_cast<long>(slowest_write_us.load()));
}

}  // namespace
}  // namespace auv::foxglove_bridge
