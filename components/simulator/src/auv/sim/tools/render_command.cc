// `auv sim render <run-dir> ...`: the camera videos of a simulated run, rendered offline from
// its ground-truth trajectory (see camera/render_run.h for the folder layout).
#include <cmath>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include "auv/config/errors.h"
#include "auv/sim/camera/render_run.h"
#include "auv/sim/common/yaml_section.h"
#include "auv/sim/tools/cli_args.h"
#include "auv/sim/tools/commands.h"

namespace auv::sim {
namespace {

const char* kRenderUsage =
    "usage: auv sim render <run-dir> [--cameras left,right] [--threads N] [--scale F]\n"
    "                      [--max-frames N] [--start S] [--end S] [--progress-every S]\n"
    "                      [--quiet]\n"
    "Renders <run-dir>/vehicle/recordings/<camera>/<camera>_0001.mp4 (+ .frames.csv) for each\n"
    "camera of the run's scenario.yaml from ground_truth/trajectory.tum, and writes the\n"
    "ground truth ground_truth/cameras.txt and images_<camera>.txt (COLMAP text format).\n"
    "  --cameras a,b    only these cameras (default: all of the scenario's rig)\n"
    "  --threads N      frames rendered at once (default: every core)\n"
    "  --scale F        resolution factor, e.g. 0.5 (default 1)\n"
    "  --max-frames N   at most N frames per camera (default: the whole run)\n"
    "  --start S, --end S   only this span of simulation time (s)\n"
    "  --progress-every S   a progress line (frames, fps, time left) every S s of wall\n"
    "                   time (default 2)\n"
    "  --quiet          no progress output\n";

int64_t parseCount(const std::string& option, const std::string& text) {
  const double value = parseNumber(option, text);
  if (value < 0 || value != std::floor(value) || value > 1e12) {
    throw UsageError(option + ": expected a whole number >= 0, got '" + text + "'");
  }
  return static_cast<int64_t>(value);
}

std::vector<std::string> splitList(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (!item.empty()) items.push_back(item);
  }
  if (items.empty()) throw UsageError("--cameras: expected a list like left,right");
  return items;
}

}  // namespace

int renderMain(const std::vector<std::string>& args) {
  std::string run_dir;
  RenderRunOptions options;
  bool quiet = false;
  try {
    for (size_t i = 0; i < args.size(); ++i) {
      const std::string& arg = args[i];
      if (arg == "-h" || arg == "--help") {
        std::cout << kRenderUsage;
        return 0;
      }
      auto value = [&]() -> const std::string& {
        if (i + 1 >= args.size()) throw UsageError(arg + ": needs a value");
        return args[++i];
      };
      if (arg == "--cameras") {
        options.cameras = splitList(value());
      } else if (arg == "--threads") {
        options.threads = static_cast<int>(parseCount(arg, value()));
        if (options.threads < 1 || options.threads > 1024)
          throw UsageError("--threads: expected 1..1024");
      } else if (arg == "--scale") {
        options.scale = parseNumber(arg, value());
        if (!(options.scale > 0 && options.scale <= 8))
          throw UsageError("--scale: expected (0, 8]");
      } else if (arg == "--max-frames") {
        options.max_frames = parseCount(arg, value());
      } else if (arg == "--start") {
        options.start_time = parseNumber(arg, value());
      } else if (arg == "--end") {
        options.end_time = parseNumber(arg, value());
      } else if (arg == "--progress-every") {
        options.progress_interval = parseNumber(arg, value());
        if (!(options.progress_interval > 0 && options.progress_interval <= 86400))
          throw UsageError("--progress-every: expected seconds in (0, 86400]");
      } else if (arg == "--quiet") {
        quiet = true;
      } else if (!arg.empty() && arg[0] == '-') {
        throw UsageError("unknown option " + arg);
      } else if (run_dir.empty()) {
        run_dir = arg;
      } else {
        throw UsageError("unexpected argument '" + arg + "' (one run folder only)");
      }
    }
    if (run_dir.empty()) throw UsageError("missing the run folder");
    if (options.end_time < options.start_time) throw UsageError("--end is before --start");
  } catch (const UsageError& e) {
    std::cerr << "auv sim render: " << e.what()
              << " (usage: auv sim render <run-dir> [options]; --help for more)\n";
    return 2;
  }
  if (!quiet) options.log = &std::cout;

  try {
    const RenderRunReport report = renderRun(run_dir, options);
    for (const RenderedVideo& video : report.videos) {
      std::cout << "render: " << video.camera << ": " << video.frames << " frames (" << video.fourcc
                << ", sim time " << video.first_sim_time << " .. " << video.last_sim_time
                << " s) -> " << video.video_path << "\n";
    }
    return 0;
  } catch (const std::invalid_argument& e) {  // an unknown camera or a time span off the run
    std::cerr << "auv sim render: " << e.what() << std::endl;
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "auv sim render: " << e.what() << std::endl;
    return config::exitCodeFor(e);  // bad input 2, failures 1
  }
}

}  // namespace auv::sim
