// map_gaps: how wide the gaps of a row of structures (the breakwater's blocks) are on a
// vehicle's own map, next to their true width: the evidence for paths that go round the row.
//
//   map_gaps --true true.bt --map own.bt --depth Z [--row-x 0] [--half-length 5]
//
// The gaps are the free stretches (1-6 m) between occupied faces along y on the true map at
// x = row-x (the row runs along y, NED east). For each, the narrowest free stretch of the own
// map across the gap's centre (±1 m) between x = row-x ± half-length, 1 m apart: the room the
// planner sees (it keeps its clearance from voxel boxes). Unknown space counts as free; a voxel
// counts when it is occupied within half a voxel of the depth.
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <octomap/OcTree.h>

#include "map_gaps.h"

namespace {

const char* kUsage =
    "usage: map_gaps --true true.bt --map own.bt --depth Z [--row-x X] [--half-length L]\n"
    "Prints, per gap of the row (free 1-6 m between occupied faces along y at x = X on the true\n"
    "map), its true width and the narrowest free width of the own map across it for x in\n"
    "[X - L, X + L] (1 m apart). Defaults: X 0, L 5. Exit 1 on a bad map, 2 on bad arguments.\n";

std::unique_ptr<octomap::OcTree> readMap(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw std::runtime_error(path + ": no such file");
  auto map = std::make_unique<octomap::OcTree>(0.1);
  if (!map->readBinary(path)) throw std::runtime_error(path + ": not an OctoMap .bt file");
  return map;
}

double parseNumber(const std::string& option, const char* text) {
  char* end = nullptr;
  const double value = std::strtod(text, &end);
  if (*text == '\0' || *end != '\0' || !std::isfinite(value)) {
    throw std::invalid_argument(option + ": expected a number, got '" + text + "'");
  }
  return value;
}

}  // namespace

int main(int argc, char** argv) {
  std::string true_path, own_path;
  std::optional<double> depth;
  double row_x = 0.0, half_length = 5.0;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      if (arg == "-h" || arg == "--help") {
        std::cout << kUsage;
        return 0;
      }
      if (i + 1 >= argc) throw std::invalid_argument(arg + ": needs a value");
      const char* value = argv[++i];
      if (arg == "--true") {
        true_path = value;
      } else if (arg == "--map") {
        own_path = value;
      } else if (arg == "--depth") {
        depth = parseNumber(arg, value);
      } else if (arg == "--row-x") {
        row_x = parseNumber(arg, value);
      } else if (arg == "--half-length") {
        half_length = parseNumber(arg, value);
        if (half_length < 0.0) throw std::invalid_argument("--half-length: expected >= 0");
      } else {
        throw std::invalid_argument("unknown argument '" + arg + "'");
      }
    }
    if (true_path.empty() || own_path.empty() || !depth) {
      throw std::invalid_argument("--true, --map and --depth are required");
    }
  } catch (const std::invalid_argument& e) {
    std::cerr << "map_gaps: " << e.what() << " (--help for usage)\n";
    return 2;
  }
  try {
    const auto truth = readMap(true_path);
    const auto own = readMap(own_path);
    const auto gaps = auv::planning::bench::measureGaps(*truth, *own, *depth, row_x, half_length);
    std::cout << std::fixed << std::setprecision(2);
    for (const auto& gap : gaps) {
      std::cout << "gap at y " << gap.centre << " m: true " << gap.true_width << " m, own map ";
      if (!gap.own_width) {
        std::cout << "not measurable (a side unmapped)\n";
      } else {
        std::cout << *gap.own_width << " m" << (*gap.own_width == 0.0 ? " (closed)" : "") << "\n";
      }
    }
    if (gaps.empty()) std::cout << "no gap of 1-6 m at x " << row_x << "\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "map_gaps: " << e.what() << "\n";
    return 1;
  }
}
