// A mission bag replayed into a fresh mapping component gives the same map (issue 22): a
// mapping component is fed odometry and sonar beams sweeping a wall while `auv bag record`'s
// Recorder records them; the bag is then played by `auv bag play`'s Player into a second,
// fresh component, and the two maps are byte-identical. Lossless on both sides (the inputs'
// qos.<topic> set to bulk_transfer): over best-effort topics a busy reader may drop beams, and
// then nothing is reproducible (components/bag/README.md, "Maps from a bag"). Domains 25, 26.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <thread>

#include "auv/bag/dds/player.h"
#include "auv/bag/dds/recorder.h"
#include "auv/interfaces/executor.h"
#include "auv/mapping/components/mapping_component.h"

namespace auv::mapping {
namespace {

using namespace std::chrono_literals;
using interfaces::Node;
using interfaces::nodeOptions;
using interfaces::Vendor;
namespace fs = std::filesystem;

const std::vector<std::string> kLossless = {"qos.nav/odometry:=bulk_transfer",
                                            "qos.sonar/beam:=bulk_transfer"};

void setStamp(msg::Header& header, int64_t ns) {
  header.stamp().sec(static_cast<int32_t>(ns / 1000000000));
  header.stamp().nanosec(static_cast<uint32_t>(ns % 1000000000));
}

/// The vehicle drives north at 0.5 m/s towards a wall at x = 9 m, 50 poses a second, and
/// sweeps a beam over +-0.6 rad between poses: `count` beams, each stamped between two poses.
void feed(Node& node, int count) {
  auto odometry = node.createPublisher<msg::Odometry>("nav/odometry", interfaces::stateQos());
  auto beams = node.createPublisher<msg::SonarBeam>("sonar/beam", interfaces::sensorDataQos());
  // Every reader (the live component and the recorder) matched before the first sample.
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  while ((odometry->matchedSubscriptions() < 2 || beams->matchedSubscriptions() < 2) &&
         std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(20ms);
  ASSERT_EQ(beams->matchedSubscriptions(), 2);
  std::this_thread::sleep_for(500ms);  // matched both ways
  const int64_t t0 = 1'000'000'000'000;
  const int64_t step = 20'000'000;  // 50 Hz
  for (int i = 0; i <= count; ++i) {
    const int64_t t = t0 + i * step;
    msg::Odometry pose;
    setStamp(pose.header(), t);
    pose.header().frame_id("world");
    const double x = 0.5 * (t - t0) * 1e-9;
    pose.pose().pose().position().x(x);
    pose.pose().pose().position().z(2.0);
    pose.pose().pose().orientation().w(1.0);
    odometry->publish(pose);
    if (i == 0) continue;
    msg::SonarBeam beam;
    setStamp(beam.header(), t - step / 2);
    beam.header().frame_id("sonar");
    beam.mounting().orientation().w(1.0);
    const double angle = 0.6 * std::sin(0.37 * i);
    beam.beam_angle(static_cast<float>(angle));
    beam.min_range(0.5f);
    beam.max_range(20.0f);
    beam.ranges({static_cast<float>((9.0 - x) / std::cos(angle))});
    beam.flags(msg::SONAR_BEAM_ECHO_RETURNED);
    beams->publish(beam);
    std::this_thread::sleep_for(2ms);
  }
  odometry->waitForAcknowledgments(10.0);
  beams->waitForAcknowledgments(10.0);
}

/// A mapping component spun on its own thread until `done`.
struct Mapping {
  Node node;
  MappingComponent component;
  interfaces::Executor executor;
  std::atomic<bool> done{false};
  std::thread spinner;
  Mapping(Vendor vendor, int domain) : node("mapping", nodeOptions(vendor, domain, kLossless)) {
    component.configure(node);
    executor.add(node);
    component.activate();
    spinner = std::thread([this] { executor.spinUntil([this] { return done.load(); }, 1h); });
  }
  /// Waits until `beams` beams went in or were dropped, stops spinning; the map as .ot bytes.
  std::string mapAfter(uint64_t beams) {
    const auto deadline = std::chrono::steady_clock::now() + 60s;
    while (component.beamsInserted() + component.beamsDropped() < beams &&
           std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(20ms);
    done = true;
    spinner.join();
    component.deactivate();
    EXPECT_EQ(component.beamsInserted(), beams);
    return component.builder().fullWithProbabilities();
  }
};

TEST(MappingBagReplay, AMissionBagReplayedIntoAFreshComponentGivesTheSameMap) {
  const fs::path bag =
      fs::temp_directory_path() / ("auv_mapping_replay_" + std::to_string(::getpid()) + ".mcap");
  constexpr int kBeams = 400;
  std::string live_map;
  {
    Mapping live(Vendor::CYCLONEDDS, 25);
    bag::RecorderOptions record;
    record.output = bag.string();
    record.domain_id = 25;
    record.topics = {"/nav/odometry", "/sonar/beam"};
    record.overwrite = true;
    bag::Recorder recorder(record);
    recorder.start();
    Node feeder("feeder", nodeOptions(Vendor::FASTDDS, 25, kLossless));
    feed(feeder, kBeams);
    live_map = live.mapAfter(kBeams);
    recorder.stop();
    for (const auto& topic : recorder.stats().topics) EXPECT_EQ(topic.lost, 0u) << topic.topic;
  }

  Mapping replayed(Vendor::FASTDDS, 26);
  bag::PlayerOptions play;
  play.input = bag.string();
  play.domain_id = 26;
  play.rate = 4.0;
  // The fresh component's readers exist already: start once they matched (across vendors on a
  // busy machine that can take seconds; a reader that matches late misses the first beams).
  play.wait_for_readers = true;
  play.delay_s = 20.0;
  play.qos_overrides = {"/nav/odometry=bulk_transfer", "/sonar/beam=bulk_transfer"};
  std::atomic<bool> stop{false};
  const auto stats = bag::Player(play).play(stop);
  EXPECT_EQ(stats.per_topic.at("/sonar/beam"), static_cast<uint64_t>(kBeams));
  const std::string replayed_map = replayed.mapAfter(kBeams);
  EXPECT_GT(live_map.size(), 100u);
  EXPECT_TRUE(replayed_map == live_map) << "the replayed map differs (" << replayed_map.size()
                                        << " against " << live_map.size() << " bytes)";
  fs::remove(bag);
}

}  // namespace
}  // namespace auv::mapping
