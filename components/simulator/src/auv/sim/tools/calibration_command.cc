// `auv sim calibration <scenario.yaml> --out DIR ...`: underwater chessboard sequences with
// each camera's true lens, for checking the calibration tool (camera/calibration_sequence.h).
#include <cmath>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include "auv/config/errors.h"
#include "auv/sim/camera/calibration_sequence.h"
#include "auv/sim/camera/camera_rig.h"
#include "auv/sim/tools/cli_args.h"
#include "auv/sim/tools/commands.h"
#include "auv/sim/world/scenario.h"

namespace auv::sim {
namespace {

const char* kCalibrationUsage =
    "usage: auv sim calibration <scenario.yaml> --out DIR [--cameras left,right] [--frames N]\n"
    "                           [--scale F] [--seed N] [--threads N] [--quiet]\n"
    "Renders, for each camera of the scenario, a chessboard (9x6 inner corners, 60 mm squares)\n"
    "moved 0.8-2 m in front of it in the scenario's water: DIR/<camera>.mp4 (+ .frames.csv)\n"
    "and the true intrinsics DIR/<camera>_truth.yaml (OpenCV FileStorage).\n"
    "  --cameras a,b   only these cameras (default: all)\n"
    "  --frames N      frames per camera (default 60)\n"
    "  --scale F       resolution factor (default 1)\n"
    "  --seed N        board poses (default 1)\n"
    "  --threads N     rendering threads (default: every core)\n"
    "  --quiet         no progress output\n";

int64_t parseCount(const std::string& option, const std::string& text, int64_t min, int64_t max) {
  const double value = parseNumber(option, text);
  if (value < min || value > max || value != std::floor(value)) {
    throw UsageError(option + ": expected a whole number in [" + std::to_string(min) + ", " +
                     std::to_string(max) + "], got '" + text + "'");
  }
  return static_cast<int64_t>(value);
}

}  // namespace

int calibrationMain(const std::vector<std::string>& args) {
  std::string scenario_path, out_dir;
  std::vector<std::string> cameras;
  CalibrationSequenceOptions options;
  bool quiet = false;
  try {
    for (size_t i = 0; i < args.size(); ++i) {
      const std::string& arg = args[i];
      if (arg == "-h" || arg == "--help") {
        std::cout << kCalibrationUsage;
        return 0;
      }
      auto value = [&]() -> const std::string& {
        if (i + 1 >= args.size()) throw UsageError(arg + ": needs a value");
        return args[++i];
      };
      if (arg == "--out") {
        out_dir = value();
      } else if (arg == "--cameras") {
        std::stringstream list(value());
        for (std::string id; std::getline(list, id, ',');) {
          if (!id.empty()) cameras.push_back(id);
        }
        if (cameras.empty()) throw UsageError("--cameras: expected a list like left,right");
      } else if (arg == "--frames") {
        options.frames = static_cast<int>(parseCount(arg, value(), 1, 100000));
      } else if (arg == "--scale") {
        options.scale = parseNumber(arg, value());
        if (!(options.scale > 0 && options.scale <= 8))
          throw UsageError("--scale: expected (0, 8]");
      } else if (arg == "--seed") {
        options.seed = static_cast<uint64_t>(parseCount(arg, value(), 0, 1LL << 53));
      } else if (arg == "--threads") {
        options.threads = static_cast<int>(parseCount(arg, value(), 1, 1024));
      } else if (arg == "--quiet") {
        quiet = true;
      } else if (!arg.empty() && arg[0] == '-') {
        throw UsageError("unknown option " + arg);
      } else if (scenario_path.empty()) {
        scenario_path = arg;
      } else {
        throw UsageError("unexpected argument '" + arg + "' (one scenario only)");
      }
    }
    if (scenario_path.empty()) throw UsageError("missing the scenario file");
    if (out_dir.empty()) throw UsageError("missing --out DIR");
  } catch (const UsageError& e) {
    std::cerr
        << "auv sim calibration: " << e.what()
        << " (usage: auv sim calibration <scenario.yaml> --out DIR [options]; --help for more)\n";
    return 2;
  }
  if (!quiet) options.log = &std::cout;

  try {
    const Scenario scenario = loadScenario(scenario_path);
    const CameraRig rig = CameraRig::fromScenario(scenario);
    const IlluminationOptions illumination = IlluminationOptions::fromScenario(scenario);
    std::vector<const CameraOptions*> selected;
    try {
      for (const std::string& id : cameras.empty() ? rig.ids() : cameras) {
        selected.push_back(&rig.camera(id));
      }
    } catch (const std::invalid_argument& e) {
      std::cerr << "auv sim calibration: " << e.what() << std::endl;
      return 2;
    }
    for (const CameraOptions* camera : selected) {
      const CalibrationSequenceReport report =
          renderCalibrationSequence(*camera, scenario.water, illumination, options, out_dir);
      std::cout << "calibration: " << report.camera << ": " << report.frames << " frames -> "
                << report.video_path << ", truth " << report.truth_path << "\n";
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "auv sim calibration: " << e.what() << std::endl;
    return config::exitCodeFor(e);  // bad input 2, failures 1
  }
}

}  // namespace auv::sim
