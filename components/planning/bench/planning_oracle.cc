// planning_oracle: the shortest collision-free path length between two points on a fully known
// map (oracle.h), for "executed path length / shortest possible" figures.
//
//   planning_oracle --map true.bt --start x,y,z --goal x,y,z --clearance planner|M
//                   [--fixed-depth] [--grid 0.2] [--min-depth 0] [--max-depth M] [--pad 0]
//                   [--csv path.csv]
//                   [--bottleneck] [--quiet]
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <string>

#include <octomap/OcTree.h>

#include "bench_common.h"
#include "oracle.h"

namespace {

using auv::planning::bench::OracleError;
using auv::planning::bench::OracleOptions;
using auv::planning::bench::PlannerSettings;
using auv::planning::bench::ShortestPathOracle;

const char* kUsage =
    "usage: planning_oracle --map true.bt --start x,y,z --goal x,y,z --clearance planner|M\n"
    "                       [--fixed-depth] [--grid M] [--min-depth M] [--max-depth M]\n"
    "                       [--pad M] [--csv FILE]\n"
    "                       [--bottleneck] [--quiet]\n"
    "Prints the length of the shortest path start -> goal keeping --clearance metres from every\n"
    "occupied voxel of a fully known map (`auv sim octomap`); unknown space counts as free.\n"
    "  --clearance M   metres, or `planner`: the planning component's hull_radius +\n"
    "                  safety_margin defaults\n"
    "  --fixed-depth   stay in the horizontal plane at the start's depth (goal moved onto it)\n"
    "  --grid M        search grid step (default 0.2; a multiple of the map resolution is best)\n"
    "  --min-depth M   no point above this depth (default 0, the surface)\n"
    "  --max-depth M   no point below this depth (default: the map's deepest; a mission's\n"
    "                  depth band is [--min-depth, --max-depth])\n"
    "  --pad M         grow the map's known box by M (free space): for a vehicle's own map,\n"
    "                  whose start may lie just outside what its sonar saw (default 0)\n"
    "  --csv FILE      also write the polyline (x,y,z per line, NED m)\n"
    "  --bottleneck    print instead the largest clearance (<= --clearance, to 0.01 m) at\n"
    "                  which start and goal are joined: the narrowest passage's half-width\n"
    "  --quiet         print the length only\n"
    "Exit status: 0 found, 1 no path or a map/query problem, 2 bad arguments.\n";

struct UsageError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

double parseNumber(const std::string& option, const std::string& text) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(value)) {
    throw UsageError(option + ": expected a number, got '" + text + "'");
  }
  return value;
}

Eigen::Vector3d parsePoint(const std::string& option, const std::string& text) {
  std::stringstream list(text);
  Eigen::Vector3d point;
  std::string item;
  int count = 0;
  while (std::getline(list, item, ',')) {
    if (count == 3) break;
    point[count++] = parseNumber(option, item);
  }
  if (count != 3 || std::getline(list, item, ',')) {
    throw UsageError(option + ": expected x,y,z (m NED), got '" + text + "'");
  }
  return point;
}

}  // namespace

int main(int argc, char** argv) {
  std::string map_path, csv_path;
  Eigen::Vector3d start, goal;
  bool have_start = false, have_goal = false, have_clearance = false, fixed_depth = false;
  bool quiet = false, bottleneck = false;
  OracleOptions options;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      auto value = [&]() -> std::string {
        if (i + 1 >= argc) throw UsageError(arg + ": needs a value");
        return argv[++i];
      };
      if (arg == "-h" || arg == "--help") {
        std::cout << kUsage;
        return 0;
      } else if (arg == "--map") {
        map_path = value();
      } else if (arg == "--start") {
        start = parsePoint(arg, value());
        have_start = true;
      } else if (arg == "--goal") {
        goal = parsePoint(arg, value());
        have_goal = true;
      } else if (arg == "--clearance") {
        const std::string text = value();
        options.clearance = text == "planner"
                                ? PlannerSettings::componentDefaults().clearance.clearance()
                                : parseNumber(arg, text);
        if (options.clearance < 0.0) throw UsageError("--clearance: expected metres >= 0");
        have_clearance = true;
      } else if (arg == "--grid") {
        options.grid = parseNumber(arg, value());
        if (!(options.grid >= 0.01 && options.grid <= 10.0)) {
          throw UsageError("--grid: expected metres in [0.01, 10]");
        }
      } else if (arg == "--pad") {
        options.padding = parseNumber(arg, value());
        if (options.padding < 0.0) throw UsageError("--pad: expected metres >= 0");
      } else if (arg == "--min-depth") {
        options.min_depth = parseNumber(arg, value());
      } else if (arg == "--max-depth") {
        options.max_depth = parseNumber(arg, value());
      } else if (arg == "--fixed-depth") {
        fixed_depth = true;
      } else if (arg == "--csv") {
        csv_path = value();
      } else if (arg == "--bottleneck") {
        bottleneck = true;
      } else if (arg == "--quiet") {
        quiet = true;
      } else {
        throw UsageError("unknown argument '" + arg + "'");
      }
    }
    if (map_path.empty()) throw UsageError("missing --map FILE.bt");
    if (!have_start) throw UsageError("missing --start x,y,z");
    if (!have_goal) throw UsageError("missing --goal x,y,z");
    if (!have_clearance) throw UsageError("missing --clearance M (the planner's hull + margin)");
  } catch (const UsageError& e) {
    std::cerr << "planning_oracle: " << e.what() << " (--help for usage)\n";
    return 2;
  }

  try {
    if (!std::filesystem::is_regular_file(map_path)) {
      throw OracleError(map_path + ": no such map file");
    }
    octomap::OcTree map(0.1);
    if (!map.readBinary(map_path)) throw OracleError(map_path + ": not an OctoMap .bt file");
    if (fixed_depth) options.fixed_depth = start.z();
    const auto started = std::chrono::steady_clock::now();
    ShortestPathOracle oracle(map, options);
    if (bottleneck) {
      const double widest = oracle.bottleneckClearance(start, goal);
      if (quiet) {
        std::cout << std::fixed << std::setprecision(3) << widest << "\n";
      } else {
        std::cout << std::fixed << std::setprecision(3) << "bottleneck clearance " << widest
                  << " m (searched up to " << options.clearance << " m, grid " << options.grid
                  << " m, " << (fixed_depth ? "fixed depth" : "3-D") << ")\n";
      }
      return 0;
    }
    const auto path = oracle.shortestPath(start, goal);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    if (!path.found) {
      std::cerr << "planning_oracle: no path at clearance " << options.clearance << " m (grid "
                << options.grid << " m)\n";
      return 1;
    }
    if (!csv_path.empty()) {
      std::ofstream csv(csv_path);
      csv << "x,y,z\n" << std::setprecision(10);
      for (const auto& p : path.points) csv << p.x() << "," << p.y() << "," << p.z() << "\n";
      if (!csv) throw OracleError(csv_path + ": cannot write");
    }
    if (quiet) {
      std::cout << std::fixed << std::setprecision(4) << path.length << "\n";
    } else {
      const double straight = (path.points.back() - path.points.front()).norm();
      std::cout << std::fixed << std::setprecision(3) << "length " << path.length
                << " m (straight line " << straight << " m), " << path.points.size()
                << " vertices, clearance " << options.clearance << " m, grid " << options.grid
                << " m, " << (fixed_depth ? "fixed depth" : "3-D") << ", " << path.expanded
                << " nodes expanded, " << seconds << " s\n";
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "planning_oracle: " << e.what() << "\n";
    return 1;
  }
}
