// `auv sim octomap <world|scenario.yaml> --out map.bt`: the world's TRUE occupancy as an OctoMap
// binary file, for benchmarks that need the fully known map (planner comparisons, the shortest
// path oracle). Occupied = every voxel the world mesh's surface touches (exact triangle/box
// overlap, so no voxel a triangle crosses is missed) plus the flat seabed; every other voxel of
// the box is free, so nothing inside the box is unknown.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <unordered_set>
#include <vector>

#include <octomap/OcTree.h>
#include <unistd.h>

#include "auv/config/errors.h"
#include "auv/sim/tools/cli_args.h"
#include "auv/sim/tools/commands.h"
#include "auv/sim/world/scenario.h"
#include "auv/sim/worldgen/world_generator.h"

namespace auv::sim {
namespace {

namespace fs = std::filesystem;
using Eigen::Vector3d;

const char* kOctomapUsage =
    "usage: auv sim octomap <world|scenario.yaml> --out map.bt [--seed N] [--resolution M]\n"
    "                       [--margin M] [--world-cache DIR]\n"
    "Writes the world's true occupancy as an OctoMap binary file (.bt): the mesh surface and the\n"
    "flat seabed occupied, the rest of the box free (fully known). The box is the mesh's\n"
    "horizontal extent grown by --margin, from the sea surface (or the mesh's top, if higher)\n"
    "down to the seabed. Prints the scenario path used on a line 'scenario <path>'.\n"
    "  --out FILE         the .bt file to write (written under a temporary name, then renamed)\n"
    "  --seed N           seed of a generated world (default 1)\n"
    "  --resolution M     voxel size in m, in [0.01, 10] (default 0.1)\n"
    "  --margin M         horizontal margin around the mesh in m, in [0, 1000] (default 5)\n"
    "  --world-cache DIR  where generated worlds are kept (default $AUV_WORLD_CACHE or\n"
    "                     ~/.cache/auv-inspect/worlds)\n";

struct OctomapArgs {
  std::string world;
  std::string out;
  uint64_t seed = 1;
  double resolution = 0.1;
  double margin = 5.0;
  std::string world_cache;
};

OctomapArgs parseArgs(const std::vector<std::string>& args) {
  OctomapArgs parsed;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    auto value = [&]() -> const std::string& {
      if (i + 1 >= args.size()) throw UsageError(arg + ": needs a value");
      return args[++i];
    };
    if (arg == "--out") {
      parsed.out = value();
      if (fs::path(parsed.out).extension() != ".bt") {
        throw UsageError("--out: expected a .bt file name, got '" + parsed.out + "'");
      }
    } else if (arg == "--seed") {
      const std::string& text = value();
      const double seed = parseNumber(arg, text);
      if (seed < 0 || seed != std::floor(seed) || seed > 9007199254740992.0) {
        throw UsageError("--seed: expected a whole number >= 0, got '" + text + "'");
      }
      parsed.seed = static_cast<uint64_t>(seed);
    } else if (arg == "--resolution") {
      const std::string& text = value();
      parsed.resolution = parseNumber(arg, text);
      if (!(parsed.resolution >= 0.01 && parsed.resolution <= 10.0)) {
        throw UsageError("--resolution: expected metres in [0.01, 10], got '" + text + "'");
      }
    } else if (arg == "--margin") {
      const std::string& text = value();
      parsed.margin = parseNumber(arg, text);
      if (!(parsed.margin >= 0.0 && parsed.margin <= 1000.0)) {
        throw UsageError("--margin: expected metres in [0, 1000], got '" + text + "'");
      }
    } else if (arg == "--world-cache") {
      parsed.world_cache = value();
    } else if (!arg.empty() && arg[0] == '-') {
      throw UsageError("unknown option " + arg);
    } else if (parsed.world.empty()) {
      parsed.world = arg;
    } else {
      throw UsageError("unexpected argument '" + arg + "' (one world or scenario only)");
    }
  }
  if (parsed.world.empty()) throw UsageError("missing the world name or scenario file");
  if (parsed.out.empty()) throw UsageError("missing --out FILE.bt");
  return parsed;
}

// Triangle/axis-aligned box overlap by the separating axis theorem (Akenine-Möller 2001): the
// 3 box normals, the triangle normal and the 9 edge cross products.
bool triangleOverlapsBox(const Vector3d& box_centre, double half,
                         const std::array<Vector3d, 3>& tri) {
  const std::array<Vector3d, 3> v = {tri[0] - box_centre, tri[1] - box_centre, tri[2] - box_centre};
  for (int axis = 0; axis < 3; ++axis) {
    const double lo = std::min({v[0][axis], v[1][axis], v[2][axis]});
    const double hi = std::max({v[0][axis], v[1][axis], v[2][axis]});
    if (lo > half || hi < -half) return false;
  }
  const std::array<Vector3d, 3> edges = {v[1] - v[0], v[2] - v[1], v[0] - v[2]};
  const Vector3d normal = edges[0].cross(edges[1]);
  const double plane_offset = normal.dot(v[0]);
  const double normal_radius = half * normal.cwiseAbs().sum();
  if (std::abs(plane_offset) > normal_radius) return false;
  for (const Vector3d& edge : edges) {
    for (int axis = 0; axis < 3; ++axis) {
      const Vector3d separating = Vector3d::Unit(axis).cross(edge);
      const double p0 = separating.dot(v[0]);
      const double p1 = separating.dot(v[1]);
      const double p2 = separating.dot(v[2]);
      const double radius = half * separating.cwiseAbs().sum();
      if (std::min({p0, p1, p2}) > radius || std::max({p0, p1, p2}) < -radius) return false;
    }
  }
  return true;
}

/// Inclusive key ranges of the map's box.
struct KeyBox {
  std::array<int, 3> min{};
  std::array<int, 3> max{};
};

using KeySet = std::unordered_set<octomap::OcTreeKey, octomap::OcTreeKey::KeyHash>;

/// Every voxel of `box` that a triangle of `mesh` touches.
KeySet voxeliseMesh(const Mesh& mesh, const octomap::OcTree& tree, const KeyBox& box) {
  KeySet occupied;
  const double resolution = tree.getResolution();
  // A hair larger than the voxel: a triangle lying exactly on a voxel face marks both sides.
  const double half = 0.5 * resolution * (1.0 + 1e-6);
  for (const Eigen::Vector3i& triangle : mesh.triangles) {
    std::array<Vector3d, 3> corners;
    for (int c = 0; c < 3; ++c) corners[c] = mesh.vertices[triangle[c]].cast<double>();
    std::array<int, 3> lo{}, hi{};
    bool outside = false;
    for (int axis = 0; axis < 3; ++axis) {
      const double min = std::min({corners[0][axis], corners[1][axis], corners[2][axis]});
      const double max = std::max({corners[0][axis], corners[1][axis], corners[2][axis]});
      lo[axis] = std::max<int>(box.min[axis], tree.coordToKey(min - half));
      hi[axis] = std::min<int>(box.max[axis], tree.coordToKey(max + half));
      outside |= lo[axis] > hi[axis];
    }
    if (outside) continue;
    octomap::OcTreeKey key;
    for (int x = lo[0]; x <= hi[0]; ++x) {
      for (int y = lo[1]; y <= hi[1]; ++y) {
        for (int z = lo[2]; z <= hi[2]; ++z) {
          key = octomap::OcTreeKey(x, y, z);
          const octomap::point3d centre = tree.keyToCoord(key);
          if (triangleOverlapsBox(Vector3d(centre.x(), centre.y(), centre.z()), half, corners)) {
            occupied.insert(key);
          }
        }
      }
    }
  }
  return occupied;
}

/// Builds the tree top-down: a cube inside the box with nothing occupied becomes one free leaf
/// (setting 10^8 voxels one by one would take minutes), other cubes are split down to voxels.
class BoxTreeBuilder {
 public:
  BoxTreeBuilder(octomap::OcTree& tree, const KeyBox& box, int seabed_key)
      : tree_(tree), box_(box), seabed_key_(seabed_key) {}

  void build(std::vector<octomap::OcTreeKey>& occupied) {
    // setNodeValue creates the root, with one chain of nodes down to a seabed voxel: fill()
    // splits every cube holding seabed down to voxels, so it reuses the chain as it is.
    tree_.setNodeValue(octomap::OcTreeKey(box_.min[0], box_.min[1], seabed_key_), 0.0f);
    octomap::OcTreeNode* root = tree_.getRoot();
    const int size = 1 << tree_.getTreeDepth();
    fill(root, {0, 0, 0}, size, occupied.begin(), occupied.end());
    tree_.updateInnerOccupancy();
    tree_.prune();
  }

 private:
  using KeyIterator = std::vector<octomap::OcTreeKey>::iterator;

  bool overlapsBox(const std::array<int, 3>& base, int size) const {
    for (int axis = 0; axis < 3; ++axis) {
      if (base[axis] > box_.max[axis] || base[axis] + size - 1 < box_.min[axis]) return false;
    }
    return true;
  }
  bool insideBox(const std::array<int, 3>& base, int size) const {
    for (int axis = 0; axis < 3; ++axis) {
      if (base[axis] < box_.min[axis] || base[axis] + size - 1 > box_.max[axis]) return false;
    }
    return true;
  }

  /// `node` covers the cube [base, base + size) of keys; [begin, end) are its occupied keys.
  void fill(octomap::OcTreeNode* node, const std::array<int, 3>& base, int size, KeyIterator begin,
            KeyIterator end) {
    const bool holds_seabed = base[2] <= seabed_key_ && seabed_key_ <= base[2] + size - 1;
    if (size == 1 || (begin == end && !holds_seabed && insideBox(base, size))) {
      const bool occupied = size == 1 && (begin != end || holds_seabed);
      node->setLogOdds(occupied ? tree_.getClampingThresMaxLog() : tree_.getClampingThresMinLog());
      return;
    }
    const int half = size / 2;
    // Split the keys by child: x bit -> 1, y bit -> 2, z bit -> 4 (octomap's child order).
    std::array<KeyIterator, 9> bounds;
    bounds[0] = begin;
    bounds[8] = end;
    auto lowerHalf = [&base, half](int axis) {
      return [axis, mid = base[axis] + half](const octomap::OcTreeKey& k) { return k[axis] < mid; };
    };
    bounds[4] = std::partition(begin, end, lowerHalf(2));
    for (int z = 0; z < 2; ++z) {
      bounds[4 * z + 2] = std::partition(bounds[4 * z], bounds[4 * z + 4], lowerHalf(1));
      for (int y = 0; y < 2; ++y) {
        const int first = 4 * z + 2 * y;
        bounds[first + 1] = std::partition(bounds[first], bounds[first + 2], lowerHalf(0));
      }
    }
    for (unsigned child = 0; child < 8; ++child) {
      const std::array<int, 3> child_base = {base[0] + ((child & 1) ? half : 0),
                                             base[1] + ((child & 2) ? half : 0),
                                             base[2] + ((child & 4) ? half : 0)};
      if (!overlapsBox(child_base, half)) continue;  // outside the box: unknown
      octomap::OcTreeNode* child_node = tree_.nodeChildExists(node, child)
                                            ? tree_.getNodeChild(node, child)
                                            : tree_.createNodeChild(node, child);
      fill(child_node, child_base, half, bounds[child], bounds[child + 1]);
    }
  }

  octomap::OcTree& tree_;
  KeyBox box_;
  int seabed_key_;
};

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

int octomapMain(const std::vector<std::string>& args) {
  if (std::find_if(args.begin(), args.end(),
                   [](const std::string& a) { return a == "-h" || a == "--help"; }) != args.end()) {
    std::cout << kOctomapUsage;
    return 0;
  }
  OctomapArgs parsed;
  try {
    parsed = parseArgs(args);
  } catch (const UsageError& e) {
    std::cerr << "auv sim octomap: " << e.what()
              << " (usage: auv sim octomap <world|scenario.yaml> --out map.bt [options]; --help "
                 "for more)\n";
    return 2;
  }

  const auto started = std::chrono::steady_clock::now();
  fs::path temporary;
  try {
    const std::string cache = parsed.world_cache.empty() ? defaultWorldCache() : parsed.world_cache;
    const std::string scenario_path = ensureWorld(parsed.world, parsed.seed, cache);
    std::cout << "scenario " << fs::absolute(scenario_path).lexically_normal().string()
              << std::endl;
    const Scenario scenario = loadScenario(scenario_path);
    const Mesh mesh = loadWorldMesh(scenario);
    const Eigen::AlignedBox3f bounds = meshBounds(mesh);

    octomap::OcTree tree(parsed.resolution);
    // Box: the mesh's horizontal extent plus the margin; from the surface (or the mesh's top
    // when it sticks out of the water) down to the seabed layer.
    const Vector3d low(bounds.min().x() - parsed.margin, bounds.min().y() - parsed.margin,
                       std::min(0.0, static_cast<double>(bounds.min().z())));
    const Vector3d high(bounds.max().x() + parsed.margin, bounds.max().y() + parsed.margin,
                        scenario.seabed_depth);
    if (!(high.z() > low.z())) {
      throw std::runtime_error(scenario.file + ": world.seabed_depth " +
                               std::to_string(scenario.seabed_depth) +
                               " m is above the surface and the mesh: no water to map");
    }
    octomap::OcTreeKey low_key, high_key;
    if (!tree.coordToKeyChecked(octomap::point3d(low.x(), low.y(), low.z()), low_key) ||
        !tree.coordToKeyChecked(octomap::point3d(high.x(), high.y(), high.z()), high_key)) {
      throw std::runtime_error("the world does not fit an OcTree at " +
                               std::to_string(parsed.resolution) + " m: use a coarser resolution");
    }
    KeyBox box;
    for (int axis = 0; axis < 3; ++axis) {
      box.min[axis] = low_key[axis];
      box.max[axis] = high_key[axis];
    }
    const int seabed_key = high_key[2];

    const KeySet occupied_set = voxeliseMesh(mesh, tree, box);
    std::vector<octomap::OcTreeKey> occupied(occupied_set.begin(), occupied_set.end());
    BoxTreeBuilder(tree, box, seabed_key).build(occupied);

    const fs::path out(parsed.out);
    if (out.has_parent_path()) fs::create_directories(out.parent_path());
    temporary = out;
    temporary += ".tmp-" + std::to_string(::getpid());
    if (!tree.writeBinary(temporary.string())) {
      throw std::runtime_error(parsed.out + ": cannot write the map");
    }
    fs::rename(temporary, out);
    temporary.clear();

    const double voxel = parsed.resolution;
    const long long cells = static_cast<long long>(box.max[0] - box.min[0] + 1) *
                            (box.max[1] - box.min[1] + 1) * (box.max[2] - box.min[2] + 1);
    std::cout << std::fixed << std::setprecision(2) << "map " << parsed.out << ": resolution "
              << voxel << " m, box NED [" << tree.keyToCoord(low_key).x() - 0.5 * voxel << ", "
              << tree.keyToCoord(low_key).y() - 0.5 * voxel << ", "
              << tree.keyToCoord(low_key).z() - 0.5 * voxel << "] .. ["
              << tree.keyToCoord(high_key).x() + 0.5 * voxel << ", "
              << tree.keyToCoord(high_key).y() + 0.5 * voxel << ", "
              << tree.keyToCoord(high_key).z() + 0.5 * voxel << "] m, " << cells << " voxels, "
              << occupied.size() << " on the mesh surface, seabed at " << scenario.seabed_depth
              << " m, " << tree.size() << " tree nodes, " << secondsSince(started) << " s"
              << std::endl;
    return 0;
  } catch (const std::exception& e) {
    std::error_code ignored;
    if (!temporary.empty()) fs::remove(temporary, ignored);
    std::cerr << "auv sim octomap: " << e.what() << std::endl;
    return config::exitCodeFor(e);  // bad input 2, failures 1
  }
}

}  // namespace auv::sim
