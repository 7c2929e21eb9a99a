// Rebuilds a mission's map from its bag (`vehicle.yaml record:=true`): a fresh `mapping`
// component, in this process, is fed the bag's navigation and sonar topics by `auv bag play`'s
// Player at the recorded pace (or --rate), follows the recorded `clock`, and its map is saved
// as a .bt — so a map can be rebuilt with other parameters from last week's dive, and so the
// mapping's determinism is checked: --compare-live compares it with the live mapping's last
// map (rebuilt from the bag's map/update), --compare with a .bt (components/bag/README.md,
// "Maps from a bag").
//
//   map_from_bag BAG.mcap OUT.bt [--compare REF.bt] [--compare-live] [--rate R] [--domain N]
//                [--vendor V] [--live-qos] [name:=value ...]   (mapping parameters)
#include <octomap/OcTree.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "auv/bag/dds/player.h"
#include "auv/config/errors.h"
#include "auv/config/yaml_scalars.h"
#include "auv/interfaces/executor.h"
#include "auv/interfaces/node.h"
#include "auv/interfaces/serialized.h"
#include "auv/mapping/components/mapping_component.h"
#include "auv/mapping/map_replica.h"

namespace {

using namespace std::chrono_literals;

constexpr const char* kUsage =
    "usage: map_from_bag BAG.mcap OUT.bt [--compare REF.bt] [--compare-live] [--rate R]\n"
    "                    [--domain N] [--vendor V] [--live-qos] [name:=value ...]\n"
    "  Feeds the bag's nav/odometry, sonar/beam, sonar/scan, dvl/beams and clock to a fresh\n"
    "  mapping component (use_sim_time) and saves its map. name:=value sets a mapping\n"
    "  parameter (vehicle.yaml's: resolution:=0.5 prob_hit:=0.85 clamping_min:=0.25\n"
    "  clamping_max:=0.9). The sensor inputs go reliable and keep-all on both sides\n"
    "  (bulk_transfer) unless --live-qos keeps the recorded QoS and the mapping's defaults.\n"
    "  --compare-live: against the live mapping's last map, rebuilt from the bag's map/update.\n"
    "  Default domain 44 (test/README.md), vendor AUV_DDS. Exit 0 when the maps compared agree\n"
    "  cell for cell, 1 when not.\n";

const std::vector<std::string> kInputs = {"/nav/odometry", "/sonar/beam", "/sonar/scan",
                                          "/dvl/beams", "/clock"};

std::string fileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

double seconds(const auv::msg::Time& t) { return t.sec() + 1e-9 * t.nanosec(); }

/// The live mapping's last map, as its readers had it: every `map/update` of the bag applied
/// in order to a replica (what the mission handler and the planner held); the newest
/// measurement time it includes, and how many beams of the bag are newer.
struct LiveMap {
  std::unique_ptr<auv::mapping::MapReplica> replica;
  double stamp_s = 0;
  uint64_t updates = 0, beams_after = 0;
};

LiveMap liveMap(const std::string& bag, double resolution) {
  LiveMap live;
  live.replica = std::make_unique<auv::mapping::MapReplica>("octomap", resolution);
  auv::bag::McapReader reader;
  reader.open(bag);
  auv::bag::ReadFilter filter;
  filter.topics = {"/map/update"};
  auto updates = reader.messages(filter);
  const auto& update_type = auv::interfaces::typeSupportByName("OctomapUpdate");
  auv::msg::OctomapUpdate update;
  while (auto m = updates.next()) {
    if (!auv::interfaces::decodeSerialized(update_type, m->message.data, &update)) continue;
    if (live.replica->apply(update) == auv::mapping::MapReplica::Outcome::APPLIED) {
      ++live.updates;
      live.stamp_s = seconds(update.header().stamp());
    }
  }
  filter.topics = {"/sonar/beam"};
  auto beams = reader.messages(filter);
  const auto& beam_type = auv::interfaces::typeSupportByName("SonarBeam");
  auv::msg::SonarBeam beam;
  while (auto m = beams.next())
    if (auv::interfaces::decodeSerialized(beam_type, m->message.data, &beam) &&
        seconds(beam.header().stamp()) > live.stamp_s)
      ++live.beams_after;
  return live;
}

/// Cells (at the finest depth) occupied in `a` and not in `b`.
size_t occupiedOnlyIn(const octomap::OcTree& a, const octomap::OcTree& b) {
  size_t count = 0;
  const double resolution = a.getResolution();
  for (auto it = a.begin_leafs(), end = a.end_leafs(); it != end; ++it) {
    if (!a.isNodeOccupied(*it)) continue;
    const int per_side = static_cast<int>(it.getSize() / resolution + 0.5);
    for (int i = 0; i < per_side; ++i)
      for (int j = 0; j < per_side; ++j)
        for (int k = 0; k < per_side; ++k) {
          const auto offset = [&](int n) {
            return static_cast<float>((n + 0.5 - per_side / 2.0) * resolution);
          };
          const octomap::point3d p =
              it.getCoordinate() + octomap::point3d(offset(i), offset(j), offset(k));
          const octomap::OcTreeNode* node = b.search(p);
          if (!node || !b.isNodeOccupied(node)) ++count;
        }
  }
  return count;
}

size_t occupiedCells(const octomap::OcTree& tree) {
  size_t count = 0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    const size_t per_side = static_cast<size_t>(it.getSize() / tree.getResolution() + 0.5);
    count += per_side * per_side * per_side;
  }
  return count;
}

/// Prints how `rebuilt` compares with `reference`; true when their occupied cells agree.
bool compareCells(const octomap::OcTree& rebuilt, const octomap::OcTree& reference,
                  const std::string& label) {
  const size_t only_rebuilt = occupiedOnlyIn(rebuilt, reference);
  const size_t only_reference = occupiedOnlyIn(reference, rebuilt);
  std::printf(
      "  against %s: occupied cells rebuilt %zu, reference %zu; only in rebuilt %zu, "
      "only in reference %zu\n",
      label.c_str(), occupiedCells(rebuilt), occupiedCells(reference), only_rebuilt,
      only_reference);
  return only_rebuilt == 0 && only_reference == 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> positional, overrides = {"use_sim_time:=true"};
  std::string compare;
  bool live_qos = false, compare_live = false;
  auv::bag::PlayerOptions play;
  play.domain_id = 44;
  play.delay_s = 20.0;
  play.wait_for_readers = true;  // the component's readers exist before the player starts
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      const auto value = [&]() -> std::string {
        if (i + 1 >= argc) throw std::invalid_argument(arg + ": needs a value");
        return argv[++i];
      };
      if (arg == "-h" || arg == "--help") {
        std::fputs(kUsage, stdout);
        return 0;
      } else if (arg == "--compare") {
        compare = value();
      } else if (arg == "--compare-live") {
        compare_live = true;
      } else if (arg == "--live-qos") {
        live_qos = true;
      } else if (arg == "--rate") {
        const auto rate = auv::config::parseNumber(value());
        if (!rate) throw std::invalid_argument("--rate: expected a number");
        play.rate = *rate;
      } else if (arg == "--domain") {
        const auto domain = auv::config::parseInteger(value());
        if (!domain) throw std::invalid_argument("--domain: expected an integer");
        play.domain_id = static_cast<int>(*domain);
      } else if (arg == "--vendor") {
        play.vendor = value();
      } else if (arg.find(":=") != std::string::npos) {
        overrides.push_back(arg);
      } else if (!arg.empty() && arg[0] == '-') {
        throw std::invalid_argument("unknown option '" + arg + "'");
      } else {
        positional.push_back(arg);
      }
    }
    if (positional.size() != 2) throw std::invalid_argument("give BAG.mcap and OUT.bt");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "map_from_bag: %s\n%s", e.what(), kUsage);
    return 2;
  }
  play.input = positional[0];
  const std::string output = positional[1];

  try {
    {  // only the mapping's inputs that the bag has
      auv::bag::McapReader reader;
      reader.open(play.input);
      for (const auto& [id, channel] : reader.channels())
        for (const auto& input : kInputs)
          if (channel.topic == input) play.topics.push_back(input);
    }
    // Lossless by default: the sensor inputs reliable and keep-all on both sides (the
    // mapping's qos.<topic> parameters), so that the map depends on the bag alone and not on
    // what a best-effort reader of a busy process happened to miss.
    for (const auto& topic : play.topics) {
      if (live_qos || topic == "/clock") continue;
      play.qos_overrides.push_back(topic + "=bulk_transfer");
      overrides.push_back("qos." + topic.substr(1) + ":=bulk_transfer");
    }
    auv::bag::Player player(play);
    for (const auto& line : player.playing()) std::printf("  playing %s\n", line.c_str());

    auv::interfaces::NodeOptions node_options;
    node_options.domain_id = play.domain_id;
    if (!play.vendor.empty()) node_options.vendor = auv::interfaces::vendorFromString(play.vendor);
    node_options.overrides = overrides;
    auv::interfaces::Node node("mapping", node_options);
    auv::mapping::MappingComponent mapping;
    mapping.configure(node);
    auv::interfaces::Executor executor;
    executor.add(node);
    mapping.activate();
    std::atomic<bool> done{false};
    std::thread spinner([&] { executor.spinUntil([&] { return done.load(); }, 24h); });

    std::atomic<bool> stop{false};
    const auto stats = player.play(stop);
    // Let the component take what is still queued: until its counters stop moving for 1 s.
    uint64_t last = ~uint64_t{0};
    for (uint64_t now; (now = mapping.beamsInserted() + mapping.beamsDropped() +
                              mapping.cloudsInserted() + mapping.cloudsDropped()) != last;) {
      last = now;
      std::this_thread::sleep_for(1s);
    }
    done = true;
    spinner.join();
    mapping.deactivate();
    std::printf(
        "played %llu messages in %.1f s; beams inserted %llu, dropped %llu; clouds "
        "inserted %llu, dropped %llu\n",
        static_cast<unsigned long long>(stats.messages), stats.wall_s,
        static_cast<unsigned long long>(mapping.beamsInserted()),
        static_cast<unsigned long long>(mapping.beamsDropped()),
        static_cast<unsigned long long>(mapping.cloudsInserted()),
        static_cast<unsigned long long>(mapping.cloudsDropped()));
    for (const auto& [topic, count] : stats.per_topic)
      std::printf("  %-16s %8llu msgs\n", topic.c_str(), static_cast<unsigned long long>(count));
    if (!mapping.builder().save(output)) throw std::runtime_error("cannot write " + output);
    std::printf("wrote %s\n", output.c_str());

    const octomap::OcTree rebuilt(output);
    bool agree = true;
    if (compare_live) {
      const LiveMap live = liveMap(play.input, rebuilt.getResolution());
      std::printf(
          "the live map from the bag's map/update: %llu updates applied, newest "
          "measurement at %.3f s; %llu beams of the bag are newer\n",
          static_cast<unsigned long long>(live.updates), live.stamp_s,
          static_cast<unsigned long long>(live.beams_after));
      agree = compareCells(rebuilt, live.replica->tree(), "the live map") && agree;
    }
    if (!compare.empty()) {
      const bool identical = fileBytes(output) == fileBytes(compare);
      const octomap::OcTree reference(compare);
      if (reference.size() == 0) throw std::runtime_error("cannot read " + compare);
      std::printf("compared with %s: %s\n", compare.c_str(),
                  identical ? "byte-identical" : "bytes differ");
      agree = compareCells(rebuilt, reference, compare) && agree;
    }
    return agree ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "map_from_bag: %s\n", e.what());
    return auv::config::exitCodeFor(e);
  }
}
