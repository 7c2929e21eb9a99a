// `auv bag play` (run by `auv` as auv-bag-play): publishes an MCAP bag's topics on DDS with
// their recorded timing (or --rate), QoS and types; nodes with use_sim_time follow the
// recorded `clock` or, with --clock, the player's. A damaged bag plays what is intact and names
// each break. Exit 0 when it played (1 when damage was found, after playing), 2 for bad arguments,
// a missing or non-MCAP file, or a topic the bag does not have.
#include <atomic>
#include <csignal>
#include <cstdio>
#include <exception>
#include <string>

#include "arguments.h"
#include "auv/bag/dds/player.h"
#include "auv/config/errors.h"

namespace {

constexpr const char* kUsage =
    "usage: auv bag play FILE.mcap [options]\n"
    "  -r, --rate R           playback speed (default 1; 2 = twice as fast)\n"
    "  -l, --loop             start again at the end until Ctrl-C\n"
    "  -t, --topics TOPIC...  play only these topics (each must be in the bag)\n"
    "  --start-offset S       skip the first S seconds of the bag\n"
    "  --delay S              wait S seconds after creating the writers, for readers to\n"
    "                         match, before the first message (default 1)\n"
    "  --wait-for-readers     start as soon as every topic has a matched reader (waiting\n"
    "                         at most --delay)\n"
    "  --qos TOPIC=PROFILE    offer a named profile (sensor_data, state, map, command,\n"
    "                         bulk_transfer, viewing, latched_state, clock) instead of the\n"
    "                         recorded QoS (repeatable)\n"
    "  --clock HZ             publish clock with the bag's time at HZ, for nodes with\n"
    "                         use_sim_time (a bag without a recorded clock)\n"
    "  --vendor V             cyclonedds or fastdds (default AUV_DDS); readers of both\n"
    "                         vendors receive it\n"
    "  --domain N             DDS domain (default AUV_DOMAIN_ID, else 0)\n";

std::atomic<bool> g_stop{false};
void onSignal(int) { g_stop = true; }

}  // namespace

int main(int argc, char** argv) {
  auv::bag::PlayerOptions options;
  try {
    auv::bag::Arguments args(argc, argv);
    while (args.next()) {
      const std::string arg = args.current();
      if (arg == "-h" || arg == "--help") {
        std::fputs(kUsage, stdout);
        return 0;
      } else if (arg == "-r" || arg == "--rate") {
        options.rate = args.number();
      } else if (arg == "-l" || arg == "--loop") {
        options.loop = true;
      } else if (arg == "-t" || arg == "--topics") {
        args.values(options.topics);
      } else if (arg == "--start-offset") {
        options.start_offset_s = args.number();
      } else if (arg == "--delay") {
        options.delay_s = args.number();
      } else if (arg == "--wait-for-readers") {
        options.wait_for_readers = true;
      } else if (arg == "--qos") {
        options.qos_overrides.push_back(args.value());
      } else if (arg == "--clock") {
        options.clock_hz = args.number();
      } else if (arg == "--vendor") {
        options.vendor = args.value();
      } else if (arg == "--domain") {
        options.domain_id = static_cast<int>(args.integer());
      } else if (!arg.empty() && arg[0] == '-') {
        throw std::invalid_argument("unknown option '" + arg + "'");
      } else if (options.input.empty()) {
        options.input = arg;
      } else {
        throw std::invalid_argument("one bag at a time ('" + options.input + "' and '" + arg +
                                    "')");
      }
    }
    if (options.input.empty()) throw std::invalid_argument("no bag given");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "auv bag play: %s\n%s", e.what(), kUsage);
    return 2;
  }

  try {
    auv::bag::Player player(options);
    for (const auto& damage : player.damage())
      std::fprintf(stderr, "auv bag play: damaged: %s\n", damage.text.c_str());
    for (const auto& skipped : player.skipped())
      std::fprintf(stderr, "auv bag play: not played: %s\n", skipped.c_str());
    for (const auto& line : player.playing()) std::fprintf(stderr, "  %s\n", line.c_str());
    std::signal(SIGINT, onSignal);
    std::signal(SIGTERM, onSignal);
    const auto stats = player.play(g_stop);
    std::printf("played %llu messages in %.1f s (%d pass%s%s)\n",
                static_cast<unsigned long long>(stats.messages), stats.wall_s, stats.loops,
                stats.loops == 1 ? "" : "es", stats.stopped ? ", stopped" : "");
    for (const auto& [topic, count] : stats.per_topic)
      std::printf("  %-32s %8llu msgs\n", topic.c_str(), static_cast<unsigned long long>(count));
    if (stats.refused)
      std::printf("  refused by the middleware: %llu (keys that do not decode)\n",
                  static_cast<unsigned long long>(stats.refused));
    return player.damage().empty() ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "auv bag play: %s\n", e.what());
    return auv::config::exitCodeFor(e);
  }
}
