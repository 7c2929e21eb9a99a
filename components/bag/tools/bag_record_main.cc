// `auv bag record` (run by `auv` as auv-bag-record): records DDS topics of either vendor into
// an MCAP file until Ctrl-C / SIGTERM (or --duration), then prints what it recorded and the
// samples lost per topic. Exit 0 when the file was closed, 1 when it could not be written,
// 2 for bad arguments or an output that exists.
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <exception>
#include <filesystem>
#include <string>
#include <thread>

#include "arguments.h"
#include "auv/bag/dds/recorder.h"
#include "auv/config/errors.h"

namespace {

constexpr const char* kUsage =
    "usage: auv bag record (-a | TOPIC...) [-o FILE.mcap] [options]\n"
    "  -a, --all              every topic on the domain, including those that appear later\n"
    "  -o, --output FILE      the bag (default auv_bag_<date>_<time>.mcap; a folder, or a\n"
    "                         name ending in '/', gets that name inside, created if needed);\n"
    "                         written as FILE.part and renamed when recording stops; never\n"
    "                         overwritten unless --overwrite\n"
    "  -x, --exclude TOPIC    leave TOPIC out (repeatable)\n"
    "  --compression C        zstd (default), lz4 or none\n"
    "  --chunk-size BYTES     messages per compressed chunk (default 1048576)\n"
    "  --flush-period S       write the open chunk at least every S seconds (default 1):\n"
    "                         what a crash of the recorder can lose\n"
    "  --duration S           stop after S seconds (default: until Ctrl-C or SIGTERM)\n"
    "  --vendor V             cyclonedds or fastdds (default AUV_DDS); records both vendors'\n"
    "                         topics either way\n"
    "  --domain N             DDS domain (default AUV_DOMAIN_ID, else 0)\n"
    "  --overwrite            replace an existing FILE\n";

std::atomic<bool> g_stop{false};
void onSignal(int) { g_stop = true; }

std::string defaultName() {
  const std::time_t now = std::time(nullptr);
  char text[64];
  std::strftime(text, sizeof text, "auv_bag_%Y%m%d_%H%M%S.mcap", std::localtime(&now));
  return text;
}

}  // namespace

int main(int argc, char** argv) {
  auv::bag::RecorderOptions options;
  bool all = false;
  double duration_s = 0;
  try {
    auv::bag::Arguments args(argc, argv);
    while (args.next()) {
      const std::string arg = args.current();
      if (arg == "-h" || arg == "--help") {
        std::fputs(kUsage, stdout);
        return 0;
      } else if (arg == "-a" || arg == "--all") {
        all = true;
      } else if (arg == "-o" || arg == "--output") {
        options.output = args.value();
      } else if (arg == "-x" || arg == "--exclude") {
        options.exclude.push_back(args.value());
      } else if (arg == "--compression") {
        options.compression = args.value();
      } else if (arg == "--chunk-size") {
        options.chunk_size = static_cast<uint64_t>(args.integer());
      } else if (arg == "--flush-period") {
        options.flush_period_s = args.number();
      } else if (arg == "--duration") {
        duration_s = args.number();
        if (!(duration_s > 0)) throw std::invalid_argument("--duration: expected S > 0");
      } else if (arg == "--vendor") {
        options.vendor = args.value();
      } else if (arg == "--domain") {
        options.domain_id = static_cast<int>(args.integer());
      } else if (arg == "--overwrite") {
        options.overwrite = true;
      } else if (!arg.empty() && arg[0] == '-') {
        throw std::invalid_argument("unknown option '" + arg + "'");
      } else {
        options.topics.push_back(arg);
      }
    }
    if (all == !options.topics.empty())
      throw std::invalid_argument(all ? "give -a or topics, not both"
                                      : "no topics given (-a records every topic)");
    if (options.output.empty()) {
      options.output = defaultName();
    } else if (options.output.back() == '/' || std::filesystem::is_directory(options.output)) {
      std::filesystem::create_directories(options.output);
      options.output = (std::filesystem::path(options.output) / defaultName()).string();
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "auv bag record: %s\n%s", e.what(), kUsage);
    return 2;
  }

  try {
    std::signal(SIGINT, onSignal);
    std::signal(SIGTERM, onSignal);
    auv::bag::Recorder recorder(options);
    recorder.start();
    std::fprintf(stderr, "auv bag record: recording to %s (Ctrl-C to stop)\n",
                 options.output.c_str());
    const auto until = std::chrono::steady_clock::now() +
                       std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                           std::chrono::duration<double>(duration_s));
    while (!g_stop && (duration_s <= 0 || std::chrono::steady_clock::now() < until))
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    recorder.stop();
    const auto stats = recorder.stats();
    std::printf("%s: %llu messages, %.1f MiB, %zu topics\n", options.output.c_str(),
                static_cast<unsigned long long>(stats.writer.messages),
                static_cast<double>(stats.writer.file_bytes) / (1 << 20), stats.topics.size());
    for (const auto& topic : stats.topics) {
      std::printf("  %-32s %8llu msgs  %10.2f MiB  lost %llu%s  [%s]\n", topic.topic.c_str(),
                  static_cast<unsigned long long>(topic.messages),
                  static_cast<double>(topic.bytes) / (1 << 20),
                  static_cast<unsigned long long>(topic.lost), topic.reliable ? " (reliable)" : "",
                  topic.type.c_str());
    }
    for (const auto& skipped : stats.skipped) std::printf("  not recorded: %s\n", skipped.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "auv bag record: %s\n", e.what());
    return auv::config::exitCodeFor(e);
  }
}
