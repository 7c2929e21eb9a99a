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

namespace {

constexpr double kStep = 0.05;            // m, scan step along y
constexpr double kMinGap = 1.0;           // m, narrower free stretches are not gaps
constexpr double kMaxGap = 6.0;           // m, wider ones are open water or a block's inside
constexpr double kCentreSlack = 1.0;      // m, an own-map stretch must overlap the centre ± this
constexpr double kSearchHalfWidth = 8.0;  // m, own-map scan around the gap centre

const char* kUsage =
    "usage: map_gaps --true true.bt --map own.bt --depth Z [--row-x X] [--half-length L]\n"
    "Prints, per gap of the row (free 1-6 m between occupied faces along y at x = X on the true\n"
    "map), its true width and the narrowest free width of the own map across it for x in\n"
    "[X - L, X + L] (1 m apart). Defaults: X 0, L 5. Exit 1 on a bad map, 2 on bad arguments.\n";

struct Stretch {
  double from;  // m, y
  double to;    // m, y
};

/// Occupied within half a voxel of depth z: a horizontal profiler's map is one voxel thick,
/// and the plane's depth may lie on a voxel boundary.
bool occupiedAt(const octomap::OcTree& map, double x, double y, double z) {
  const double half = 0.5 * map.getResolution();
  for (const double dz : {0.0, -half + 1e-6, half - 1e-6}) {
    const octomap::OcTreeNode* node = map.search(x, y, z + dz);
    if (node != nullptr && map.isNodeOccupied(node)) return true;
  }
  return false;
}

/// Free stretches along y in [y0, y1] at (x, z), each bounded by occupied cells on both sides.
std::vector<Stretch> boundedFreeStretches(const octomap::OcTree& map, double x, double z, double y0,
                                          double y1) {
  std::vector<Stretch> stretches;
  double free_since = y0;
  bool in_free = false, seen_occupied = false;
  const int steps = static_cast<int>(std::floor((y1 - y0) / kStep));
  for (int i = 0; i <= steps; ++i) {
    const double y = y0 + i * kStep;
    if (occupiedAt(map, x, y, z)) {
      if (in_free && seen_occupied) stretches.push_back({free_since, y});
      in_free = false;
      seen_occupied = true;
    } else if (!in_free) {
      free_since = y;
      in_free = true;
    }
  }
  return stretches;
}

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
    double x0, y0, z0, x1, y1, z1;
    truth->getMetricMin(x0, y0, z0);
    truth->getMetricMax(x1, y1, z1);
    std::cout << std::fixed << std::setprecision(2);
    int gaps = 0;
    for (const Stretch& gap : boundedFreeStretches(*truth, row_x, *depth, y0, y1)) {
      const double width = gap.to - gap.from;
      if (width <= kMinGap || width >= kMaxGap) continue;
      ++gaps;
      const double centre = 0.5 * (gap.from + gap.to);
      std::optional<double> narrowest;
      bool closed = false;
      for (double x = row_x - half_length; x <= row_x + half_length + 1e-9; x += 1.0) {
        std::optional<double> widest_here;  // the own map's stretch across the centre
        bool bounded = false;
        for (const Stretch& s : boundedFreeStretches(*own, x, *depth, centre - kSearchHalfWidth,
                                                     centre + kSearchHalfWidth)) {
          bounded = true;
          if (s.from <= centre + kCentreSlack && s.to >= centre - kCentreSlack) {
            widest_here = std::max(widest_here.value_or(0.0), s.to - s.from);
          }
        }
        if (!bounded) continue;  // nothing mapped on both sides at this x
        if (!widest_here) closed = true;
        narrowest = std::min(narrowest.value_or(1e9), widest_here.value_or(0.0));
      }
      std::cout << "gap at y " << centre << " m: true " << width << " m, own map ";
      if (narrowest) {
        std::cout << *narrowest << " m" << (closed ? " (closed at some x)" : "") << "\n";
      } else {
        std::cout << "not bounded (a side unmapped)\n";
      }
    }
    if (gaps == 0)
      std::cout << "no gap of " << kMinGap << "-" << kMaxGap << " m at x " << row_x << "\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "map_gaps: " << e.what() << "\n";
    return 1;
  }
}
