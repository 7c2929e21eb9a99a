// `auv recon pull`: the vehicle's recordings into <survey>/recordings/ (reconstruction/README.md).
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <thread>

#include "auv/config/errors.h"
#include "auv/interfaces/executor.h"
#include "auv/recon/tools/command.h"
#include "auv/recon/transfer/progress_display.h"
#include "auv/recon/transfer/puller.h"

namespace auv::recon {
namespace {

const char* kPullUsage =
    "usage: auv recon pull --vehicle <name> --into <survey>/ [options]\n"
    "Waits for the vehicle's recorder, lists its recordings and pulls every complete one that\n"
    "is not verified in <survey>/recordings/ yet (resumable: run it again after an interruption).\n"
    "  --vehicle <name>     the recorder's vehicle_name (default auv)\n"
    "  --into <survey>      survey folder (files go to <survey>/recordings/<camera>/)\n"
    "  --timeout <s>        wait this long for the vehicle to appear or come back (default 60)\n"
    "  --in-flight <n>      chunk requests outstanding at once (default 8)\n"
    "  --chunk-bytes <b>    bytes per chunk, capped by the recorder (default 1048576)\n"
    "  --camera <id>        only this camera (repeatable)\n"
    "Exit: 0 every complete recording verified on disk; 1 some recording failed (listed) or a\n"
    "local error; 2 bad usage; 3 vehicle not found / gone for --timeout; 130 interrupted.\n";

using tools::kExitFailed;
using tools::kExitUsage;
constexpr int kExitVehicleLost = 3;
constexpr int kExitInterrupted = 130;

template <class T>
T parseNumber(const std::string& option, const std::string& text) {
  std::istringstream in(text);
  T value{};
  if (!(in >> value) || !in.eof()) {
    throw std::invalid_argument(option + ": '" + text + "' is not a number");
  }
  return value;
}

std::string summary(const transfer::PullStats& s, const std::string& result) {
  using transfer::ProgressDisplay;
  std::ostringstream out;
  out << "pull: " << result << ": " << s.recordings_pulled << " recordings pulled ("
      << s.files_pulled << " files), " << s.recordings_present << " already verified, "
      << s.recordings_failed << " failed";
  if (s.recordings_being_written > 0) {
    out << ", " << s.recordings_being_written << " still being written on the vehicle";
  }
  out << "; " << ProgressDisplay::bytes(static_cast<double>(s.bytes_received)) << " received in "
      << ProgressDisplay::duration(s.seconds);
  if (s.seconds > 0) {
    out << " (" << ProgressDisplay::bytes(s.bytes_received / s.seconds) << "/s)";
  }
  if (s.chunks_reused > 0) out << ", " << s.chunks_reused << " chunks reused from disk";
  if (s.chunks_corrupted > 0) out << ", " << s.chunks_corrupted << " corrupted chunks refetched";
  if (s.requests_timed_out > 0) out << ", " << s.requests_timed_out << " requests repeated";
  if (s.vehicle_restarts == 1) out << ", vehicle came back once";
  if (s.vehicle_restarts > 1) out << ", vehicle came back " << s.vehicle_restarts << " times";
  return out.str();
}

// Prints the summary line; returns the exit code.
int report(transfer::PullResult result, const transfer::PullStats& stats,
           const transfer::PullOptions& options) {
  switch (result) {
    case transfer::PullResult::COMPLETE:
      std::cout << summary(stats, "complete") << "; manifest "
                << (options.survey / "recordings" / "manifest.json").string() << std::endl;
      return 0;
    case transfer::PullResult::FAILED_FILES:
      std::cout << summary(stats, "incomplete") << std::endl;
      return kExitFailed;
    case transfer::PullResult::VEHICLE_LOST:
      std::cerr << "auv recon pull: " << stats.lost << "; partial files are kept, run the "
                << "same command again to resume\n";
      std::cout << summary(stats, "vehicle lost") << std::endl;
      return kExitVehicleLost;
    case transfer::PullResult::INTERRUPTED:
      std::cout << summary(stats, "interrupted") << "; run the same command again to resume"
                << std::endl;
      return kExitInterrupted;
  }
  return kExitFailed;
}

// Ends the process once the pull's DDS entities are deleted (the vehicle is told we left):
// static destructors are skipped because Fast DDS's participant factory sleeps 100 ms in its
// own, a third of pulling 100 MB on a fast link. Files, manifest and lock are already closed.
[[noreturn]] void exitSkippingStaticDestructors(int code) {
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
  std::_Exit(code);
}

// Pulls with `options`; returns the exit code once the node is gone.
int pull(const transfer::PullOptions& options, transfer::ProgressDisplay& display) {
  interfaces::Node node("recon_pull");
  transfer::Puller puller(node, options);
  puller.onProgress([&](const transfer::PullProgress& p) { display.update(p); });
  puller.onMessage([&](const std::string& text) { display.message("pull: " + text); });
  interfaces::Executor::installSignalHandlers();
  std::atomic<bool> done{false};
  std::thread watcher([&] {
    while (!done) {
      if (interfaces::Executor::signalled()) puller.stop();
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  });
  transfer::PullResult result;
  try {
    result = puller.run();
  } catch (...) {
    done = true;
    watcher.join();
    throw;
  }
  done = true;
  watcher.join();
  display.finish();
  const transfer::PullStats& stats = puller.stats();
  for (const auto& problem : stats.problems) std::cerr << "pull: failed: " << problem << "\n";
  return report(result, stats, options);
}

int pullMain(const std::vector<std::string>& args) {
  transfer::PullOptions options;
  bool have_into = false;
  try {
    for (size_t i = 0; i < args.size(); ++i) {
      const std::string& arg = args[i];
      if (arg == "--help" || arg == "-h") {
        std::cout << kPullUsage;
        return 0;
      }
      if (i + 1 >= args.size()) throw std::invalid_argument(arg + ": missing value");
      const std::string& value = args[++i];
      if (arg == "--vehicle") {
        options.vehicle = value;
      } else if (arg == "--into") {
        options.survey = value;
        have_into = true;
      } else if (arg == "--timeout") {
        options.timeout_s = parseNumber<double>(arg, value);
      } else if (arg == "--in-flight") {
        options.in_flight = parseNumber<int>(arg, value);
      } else if (arg == "--chunk-bytes") {
        options.chunk_bytes = parseNumber<uint32_t>(arg, value);
      } else if (arg == "--camera") {
        options.cameras.push_back(value);
      } else {
        --i;
        throw std::invalid_argument("unknown option '" + arg + "'");
      }
    }
    if (!have_into) throw std::invalid_argument("--into <survey>: required");
    options.check();
  } catch (const std::invalid_argument& e) {
    std::cerr << "auv recon pull: " << e.what() << "\n" << kPullUsage;
    return kExitUsage;
  }

  transfer::ProgressDisplay display(stderr, ::isatty(STDERR_FILENO) != 0);
  int code = kExitFailed;
  try {
    code = pull(options, display);
  } catch (const std::exception& e) {
    display.finish();
    std::cerr << "auv recon pull: " << e.what() << "\n";
    code = config::exitCodeFor(e);  // a bad survey folder 2, a failed pull 1
  }
  exitSkippingStaticDestructors(code);
}

}  // namespace

AUV_RECON_COMMAND("pull", 0, "--vehicle <name> --into <survey>/   pull the vehicle's recordings",
                  pullMain);

}  // namespace auv::recon
