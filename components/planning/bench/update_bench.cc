// update_bench: the cost of keeping OnlineRRTstar's tree on a changing map (docs/paper.md §2.2.2)
// and of handing out a waypoint, against tree size. For N = 1k, 2k, 5k, 10k nodes grown on a
// world's known map: updateTree() with no map change, after a new obstacle blob is inserted across
// the tree (voxels set occupied, the distance field updated as the planning component does), and
// after the blob is removed again; popWaypoint(). Anchors measured in the same run: one full
// rebuild of OMPL's NearestNeighborsGNAT with N states, and N x checkMotion over the tree's edges.
// The goal: updateTree p99 < 5 ms at 5k nodes. See bench/README.md.
//
//   update_bench [options] SCENARIO.yaml MAP.bt
#include <cmath>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>

#include <ompl/base/PlannerTerminationCondition.h>
#include <ompl/base/ScopedState.h>
#include <ompl/datastructures/NearestNeighborsGNAT.h>
#include <ompl/datastructures/NearestNeighborsGNATNoThreadSafety.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>

#include "auv/planning/online_rrt_star.h"
#include "bench_common.h"

namespace {

namespace ob = ompl::base;
using namespace auv::planning;
using namespace auv::planning::bench;
using Node = OnlineRRTstar::Node;

const char* kUsage =
    "usage: update_bench [options] SCENARIO.yaml MAP.bt\n"
    "  --sizes a,b,...      tree sizes (default 1000,2000,5000,10000)\n"
    "  --repeats N          blob insertions per size (default 200)\n"
    "  --static-repeats N   updateTree calls without a change per size (default 200)\n"
    "  --pop-repeats N      popWaypoint calls per size (default 100; each regrows the tree)\n"
    "  --blob-radius M      radius of the inserted obstacle sphere (default 1.5)\n"
    "  --quick              sizes 1000,5000, 20 / 50 / 10 repeats\n"
    "  --3d                 plan in 3-D (default: fixed depth = the first query's start depth)\n"
    "  --seed N             OMPL's global seed and the blob positions (default 1)\n"
    "  --out FILE.md        results (also FILE.csv)\n";

struct Args {
  std::string scenario, map;
  std::vector<std::size_t> sizes = {1000, 2000, 5000, 10000};
  int repeats = 200;
  int static_repeats = 200;
  int pop_repeats = 100;
  double blob_radius = 1.5;
  bool fixed_depth = true;
  std::uint32_t seed = 1;
  std::string out;
};

double parseNumber(const std::string& option, const std::string& text) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(value)) {
    throw std::invalid_argument(option + ": expected a number, got '" + text + "'");
  }
  return value;
}

int parseCount(const std::string& option, const std::string& text) {
  const double value = parseNumber(option, text);
  if (value < 1 || value > 1e7 || value != std::floor(value)) {
    throw std::invalid_argument(option + ": expected a whole number >= 1, got '" + text + "'");
  }
  return static_cast<int>(value);
}

Args parseArgs(int argc, char** argv) {
  Args args;
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(arg + ": needs a value");
      return argv[++i];
    };
    if (arg == "-h" || arg == "--help") {
      std::cout << kUsage;
      std::exit(0);
    } else if (arg == "--sizes") {
      args.sizes.clear();
      std::stringstream list(value());
      for (std::string item; std::getline(list, item, ',');) {
        args.sizes.push_back(static_cast<std::size_t>(parseCount(arg, item)));
      }
      if (args.sizes.empty()) throw std::invalid_argument("--sizes: empty list");
    } else if (arg == "--repeats") {
      args.repeats = parseCount(arg, value());
    } else if (arg == "--static-repeats") {
      args.static_repeats = parseCount(arg, value());
    } else if (arg == "--pop-repeats") {
      args.pop_repeats = parseCount(arg, value());
    } else if (arg == "--blob-radius") {
      args.blob_radius = parseNumber(arg, value());
      if (!(args.blob_radius > 0.0 && args.blob_radius <= 20.0)) {
        throw std::invalid_argument("--blob-radius: expected metres in (0, 20]");
      }
    } else if (arg == "--quick") {
      args.sizes = {1000, 5000};
      args.repeats = 20;
      args.static_repeats = 50;
      args.pop_repeats = 10;
    } else if (arg == "--3d") {
      args.fixed_depth = false;
    } else if (arg == "--seed") {
      args.seed = static_cast<std::uint32_t>(parseNumber(arg, value()));
    } else if (arg == "--out") {
      args.out = value();
    } else if (!arg.empty() && arg[0] == '-') {
      throw std::invalid_argument("unknown option " + arg);
    } else {
      files.push_back(arg);
    }
  }
  if (files.size() != 2) throw std::invalid_argument("expected SCENARIO.yaml MAP.bt");
  args.scenario = files[0];
  args.map = files[1];
  return args;
}

/// Marks a blob voxel that was unknown before (it is deleted again, not set free).
constexpr float kUnknown = std::numeric_limits<float>::quiet_NaN();

double millisecondsSince(Clock::time_point start) { return 1e3 * secondsSince(start); }

std::vector<const Node*> treeNodes(const OnlineRRTstar& planner) {
  std::vector<const Node*> nodes;
  if (planner.root() == nullptr) return nodes;
  std::vector<const Node*> stack{planner.root()};
  while (!stack.empty()) {
    const Node* node = stack.back();
    stack.pop_back();
    nodes.push_back(node);
    stack.insert(stack.end(), node->children.begin(), node->children.end());
  }
  return nodes;
}

/// Grows until the tree has `size` nodes (and a solution when asked); false after 120 s.
bool growTo(OnlineRRTstar& planner, std::size_t size, bool need_solution) {
  const auto deadline = Clock::now() + std::chrono::seconds(120);
  planner.solve(ob::PlannerTerminationCondition([&] {
    return Clock::now() >= deadline ||
           (planner.treeSize() >= size && (!need_solution || planner.bestSolution() != nullptr));
  }));
  return planner.treeSize() >= size && (!need_solution || planner.bestSolution() != nullptr);
}

/// p50 / p99 / max of milliseconds.
std::string spread(const std::vector<double>& ms) {
  return formatNumber(percentile(ms, 0.5), 3) + " / " + formatNumber(percentile(ms, 0.99), 3);
}

struct SizeResult {
  std::size_t size = 0;
  std::vector<double> static_update, blob_update, blob_removed_update, field_update, pop;
  std::vector<double> removed;
  double gnat_rebuild = 0, gnat_nts_rebuild = 0, check_motion = 0;
  int restarts = 0;
};

}  // namespace

int main(int argc, char** argv) {
  Args args;
  try {
    args = parseArgs(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "update_bench: " << e.what() << " (--help for usage)\n";
    return 2;
  }
  ompl::RNG::setSeed(args.seed);
  ompl::msg::setLogLevel(ompl::msg::LOG_ERROR);
  std::mt19937 random(args.seed);
  const std::string started = timestamp();
  const std::string load_before = machineNote();
  const auto wall = Clock::now();
  std::vector<SizeResult> results;
  PlannerSettings settings = PlannerSettings::componentDefaults();
  settings.fixed_depth = args.fixed_depth;
  std::string world;
  try {
    const BenchScenario scenario = readScenario(args.scenario);
    world = scenario.name;
    WorldMap map = loadWorldMap(args.map, settings.max_distance);
    const QueryProblem problem =
        makeQueryProblem(map, scenario.queries.front(), settings, scenario.seabed_depth);
    const auto& si = problem.si;
    const double resolution = map.tree->getResolution();
    std::cout << "update_bench on " << world << " (" << args.map << "), query "
              << scenario.queries.front().name << "; " << settings.describe() << "\n";

    for (std::size_t size : args.sizes) {
      SizeResult result;
      result.size = size;
      const ob::ProblemDefinitionPtr pdef = problem.makeProblemDefinition();
      auto planner =
          std::dynamic_pointer_cast<OnlineRRTstar>(makePlanner("OnlineRRTstar", problem, settings));
      planner->setProblemDefinition(pdef);
      planner->setup();
      const auto grow_start = Clock::now();
      if (!growTo(*planner, size, false)) throw std::runtime_error("cannot grow the tree");
      std::cout << "-- " << size << " nodes grown in " << formatNumber(secondsSince(grow_start), 2)
                << " s\n"
                << std::flush;
      ob::ScopedState<> vehicle(si);  // the vehicle sits at the root (the active waypoint)
      si->copyState(vehicle.get(), planner->root()->state);

      // Anchors: the structures and checks updateTree is made of, at the same N.
      const std::vector<const Node*> nodes = treeNodes(*planner);
      std::vector<const ob::State*> states;
      for (const Node* node : nodes) states.push_back(node->state);
      auto distance = [&si](const ob::State* a, const ob::State* b) { return si->distance(a, b); };
      std::vector<double> gnat, gnat_nts, motions;
      for (int rep = 0; rep < 5; ++rep) {
        ompl::NearestNeighborsGNAT<const ob::State*> index;
        index.setDistanceFunction(distance);
        auto t0 = Clock::now();
        index.add(states);
        gnat.push_back(millisecondsSince(t0));
        ompl::NearestNeighborsGNATNoThreadSafety<const ob::State*> index_nts;
        index_nts.setDistanceFunction(distance);
        t0 = Clock::now();
        index_nts.add(states);
        gnat_nts.push_back(millisecondsSince(t0));
        t0 = Clock::now();
        std::size_t valid = 0;
        for (const Node* node : nodes) {
          if (node->parent != nullptr) valid += si->checkMotion(node->parent->state, node->state);
        }
        motions.push_back(millisecondsSince(t0));
        if (valid + 1 != nodes.size()) std::cerr << "warning: invalid edges in a fresh tree\n";
      }
      result.gnat_rebuild = percentile(gnat, 0.5);
      result.gnat_nts_rebuild = percentile(gnat_nts, 0.5);
      result.check_motion = percentile(motions, 0.5);

      for (int rep = 0; rep < args.static_repeats; ++rep) {
        const auto t0 = Clock::now();
        planner->updateTree(vehicle.get());
        result.static_update.push_back(millisecondsSince(t0));
      }

      // A blob across the tree, away from the root so the waypoint stays valid.
      const double keep_away = args.blob_radius + settings.clearance.clearance() + resolution;
      for (int rep = 0; rep < args.repeats; ++rep) {
        if (!growTo(*planner, size, false)) throw std::runtime_error("cannot regrow the tree");
        const std::vector<const Node*> candidates = treeNodes(*planner);
        const Eigen::Vector3d root = statePosition(planner->root()->state);
        Eigen::Vector3d centre = root;
        for (int attempt = 0; attempt < 1000 && (centre - root).norm() < keep_away; ++attempt) {
          centre = statePosition(candidates[random() % candidates.size()]->state);
        }
        std::vector<std::pair<octomap::OcTreeKey, float>> changed;  // key, previous log-odds
        const int cells = static_cast<int>(std::ceil(args.blob_radius / resolution));
        const octomap::OcTreeKey centre_key =
            map.tree->coordToKey(octomap::point3d(centre.x(), centre.y(), centre.z()));
        for (int dx = -cells; dx <= cells; ++dx) {
          for (int dy = -cells; dy <= cells; ++dy) {
            for (int dz = -cells; dz <= cells; ++dz) {
              const octomap::OcTreeKey key(centre_key[0] + dx, centre_key[1] + dy,
                                           centre_key[2] + dz);
              const octomap::point3d p = map.tree->keyToCoord(key);
              if ((Eigen::Vector3d(p.x(), p.y(), p.z()) - centre).norm() > args.blob_radius) {
                continue;
              }
              const octomap::OcTreeNode* node = map.tree->search(key);
              changed.emplace_back(key, node ? node->getLogOdds() : kUnknown);
              map.tree->setNodeValue(key, map.tree->getClampingThresMaxLog());
            }
          }
        }
        auto t0 = Clock::now();
        map.field->update();
        result.field_update.push_back(millisecondsSince(t0));
        // As the planning component does: only edges near the changed box are re-checked.
        const Eigen::AlignedBox3d blob(centre.array() - args.blob_radius,
                                       centre.array() + args.blob_radius);
        const double influence =
            std::max(settings.clearance.clearance(),
                     settings.cost.expected_distance + 0.5 * settings.cost.admissible_range) +
            resolution;
        t0 = Clock::now();
        const UpdateResult update = planner->updateTree(vehicle.get(), blob, influence);
        result.blob_update.push_back(millisecondsSince(t0));
        result.removed.push_back(static_cast<double>(update.removed_nodes));
        // Take the blob out again; the re-check then only refreshes costs (nothing collides).
        for (const auto& [key, log_odds] : changed) {
          // Unknown before: beyond the known box and the distance field, so set free (OctoMap's
          // deleteNode() asserts on nodes whose children were all deleted).
          map.tree->setNodeValue(
              key, std::isnan(log_odds) ? map.tree->getClampingThresMinLog() : log_odds);
        }
        map.field->update();
        t0 = Clock::now();
        planner->updateTree(vehicle.get(), blob, influence);
        result.blob_removed_update.push_back(millisecondsSince(t0));
        if (update.needsRestart()) {  // the blob reached the root after all: start afresh
          ++result.restarts;
          planner->reset(vehicle.get());
        }
      }

      // Waypoint latency: prune to the next waypoint of the best solution.
      ob::ScopedState<> waypoint(si);
      ob::ScopedState<> start(si);
      si->copyState(start.get(), vehicle.get());
      for (int rep = 0; rep < args.pop_repeats; ++rep) {
        if (!growTo(*planner, size, true)) throw std::runtime_error("no solution to pop");
        const auto t0 = Clock::now();
        const bool popped = planner->popWaypoint(waypoint.get());
        const double ms = millisecondsSince(t0);
        if (popped) {
          result.pop.push_back(ms);
        } else {
          planner->reset(start.get());  // the root reached the goal: start the query again
          --rep;
        }
      }
      std::cout << "   updateTree no change " << spread(result.static_update) << " ms, blob "
                << spread(result.blob_update) << " ms (removed "
                << formatNumber(percentile(result.removed, 0.5), 0) << " nodes), popWaypoint "
                << spread(result.pop) << " ms\n"
                << std::flush;
      results.push_back(std::move(result));
    }
  } catch (const std::exception& e) {
    std::cerr << "update_bench: " << e.what() << "\n";
    return 1;
  }

  std::ostringstream md, csv;
  md << "# Tree update benchmark " << started << "\n\n"
     << "OnlineRRTstar on " << world << " (" << args.map << "), first query; "
     << settings.describe() << ". Blob: a sphere of radius " << args.blob_radius
     << " m set occupied around a random "
     << "tree node at least blob + clearance + one voxel from the root, then the distance field "
     << "updated (as the planning component applies a map increment) and removed again. "
     << args.static_repeats << " / " << args.repeats << " / " << args.pop_repeats
     << " repetitions (no change / blob / popWaypoint; each blob and pop regrows the tree to N "
     << "first). Machine: " << load_before << " at the start, " << machineNote()
     << " at the end (shared: other builds ran). Wall time " << formatNumber(secondsSince(wall), 0)
     << " s. Times in ms, p50 / p99.\n\n"
     << "| nodes | updateTree, no change | updateTree, blob inserted | nodes removed (median) | "
        "updateTree, blob removed | field.update(), blob (p50) | popWaypoint | anchor: GNAT "
        "rebuild, N states | GNAT without thread safety (the planner's) | anchor: N × "
        "checkMotion |\n|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  csv << "nodes,kind,ms\n";
  for (const SizeResult& r : results) {
    md << "| " << r.size << " | " << spread(r.static_update) << " | " << spread(r.blob_update)
       << " | " << formatNumber(percentile(r.removed, 0.5), 0) << " | "
       << spread(r.blob_removed_update) << " | " << formatNumber(percentile(r.field_update, 0.5), 3)
       << " | " << spread(r.pop) << " | " << formatNumber(r.gnat_rebuild, 3) << " | "
       << formatNumber(r.gnat_nts_rebuild, 3) << " | " << formatNumber(r.check_motion, 3) << " |\n";
    const std::pair<const char*, const std::vector<double>*> series[] = {
        {"update_static", &r.static_update},
        {"update_blob", &r.blob_update},
        {"update_blob_removed", &r.blob_removed_update},
        {"field_update", &r.field_update},
        {"pop_waypoint", &r.pop},
        {"removed_nodes", &r.removed}};
    for (const auto& [kind, values] : series) {
      for (double v : *values) csv << r.size << "," << kind << "," << v << "\n";
    }
    csv << r.size << ",anchor_gnat_rebuild," << r.gnat_rebuild << "\n"
        << r.size << ",anchor_gnat_nts_rebuild," << r.gnat_nts_rebuild << "\n"
        << r.size << ",anchor_check_motion," << r.check_motion << "\n";
    if (r.restarts > 0)
      md << "\n(" << r.restarts << " blobs at " << r.size
         << " nodes reached the root: tree reset)\n";
  }
  for (const SizeResult& r : results) {
    if (r.size != 5000) continue;
    const double p99 = percentile(r.blob_update, 0.99);
    md << "\nGoal (issue 4): updateTree p99 < 5 ms at 5k nodes: " << formatNumber(p99, 3)
       << " ms with a blob, " << formatNumber(percentile(r.static_update, 0.99), 3)
       << " ms without a change: " << (p99 < 5.0 ? "met" : "not met") << ".\n";
  }
  std::cout << "\n" << md.str();
  if (!args.out.empty()) {
    std::ofstream(args.out) << md.str();
    std::string csv_path = args.out;
    const auto dot = csv_path.rfind(".md");
    csv_path = (dot == std::string::npos ? csv_path : csv_path.substr(0, dot)) + ".csv";
    std::ofstream(csv_path) << csv.str();
    std::cout << "results: " << args.out << ", " << csv_path << "\n";
  }
  return 0;
}
