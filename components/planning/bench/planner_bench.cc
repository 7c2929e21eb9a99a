// planner_bench: OnlineRRTstar against OMPL's RRTstar, InformedRRTstar and BITstar on the
// worlds' static, fully known maps (`auv sim octomap`), same SpaceInformation and visibility
// objective for all, interleaved run by run so machine load hits every planner alike.
// Figures per planner and query: success rate, time to the first solution (median, p90; a
// failed run counts as slower than the budget), cost at 0.1 / 0.5 / 1.0 s (median over the
// runs that have a solution by then, with their count). See bench/README.md.
//
//   planner_bench [options] SCENARIO.yaml MAP.bt [SCENARIO.yaml MAP.bt ...]
#include <cmath>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>

#include <ompl/base/PlannerTerminationCondition.h>
#include <ompl/base/ScopedState.h>
#include <ompl/config.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/geometric/planners/informedtrees/BITstar.h>
#include <ompl/geometric/planners/rrt/RRTstar.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>

#include "auv/planning/online_rrt_star.h"
#include "bench_common.h"
#include "oracle.h"

namespace {

namespace ob = ompl::base;
namespace og = ompl::geometric;
using namespace auv::planning;
using namespace auv::planning::bench;

const char* kUsage =
    "usage: planner_bench [options] SCENARIO.yaml MAP.bt [SCENARIO.yaml MAP.bt ...]\n"
    "  --seeds N               runs per planner and query (default 50)\n"
    "  --quick                 5 runs, first query of each world\n"
    "  --budget S              seconds per run (default 1); costs at 0.1, 0.5 and the budget\n"
    "  --queries all|first     which queries of each scenario (default all)\n"
    "  --planners a,b          subset of OnlineRRTstar,RRTstar,InformedRRTstar,BITstar\n"
    "  --3d                    plan in 3-D (default: fixed depth = the query's start depth)\n"
    "  --expected-distance M   d_e of Eq. (1) (default 1)\n"
    "  --admissible-range M    Δd_a of Eq. (1) (default 1)\n"
    "  --narrow-passage-bias X OnlineRRTstar's share of bridge-test samples (default: the\n"
    "                          planning component's)\n"
    "  --max-climb-angle DEG   steepest climb of a path (default: the planning component's)\n"
    "  --seed N                OMPL's global seed (default 1)\n"
    "  --out FILE.md           results (also FILE.csv with every run)\n";

struct Args {
  std::vector<std::pair<std::string, std::string>> worlds;  // scenario, map
  int runs = 50;
  double budget = 1.0;
  bool first_query_only = false;
  std::vector<std::string> planners = plannerNames();
  bool fixed_depth = true;
  double expected_distance = 1.0;
  double admissible_range = 1.0;
  std::optional<double> narrow_passage_bias;  // unset: the component's default
  std::optional<double> max_climb_angle;      // unset: the component's default
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
    } else if (arg == "--seeds") {
      const double runs = parseNumber(arg, value());
      if (runs < 1 || runs > 100000 || runs != std::floor(runs)) {
        throw std::invalid_argument("--seeds: expected a whole number >= 1");
      }
      args.runs = static_cast<int>(runs);
    } else if (arg == "--quick") {
      args.runs = 5;
      args.first_query_only = true;
    } else if (arg == "--budget") {
      args.budget = parseNumber(arg, value());
      if (!(args.budget > 0.0 && args.budget <= 600.0)) {
        throw std::invalid_argument("--budget: expected seconds in (0, 600]");
      }
    } else if (arg == "--queries") {
      const std::string which = value();
      if (which != "all" && which != "first") {
        throw std::invalid_argument("--queries: expected all or first, got '" + which + "'");
      }
      args.first_query_only = which == "first";
    } else if (arg == "--planners") {
      args.planners.clear();
      std::stringstream list(value());
      for (std::string name; std::getline(list, name, ',');) {
        if (std::find(plannerNames().begin(), plannerNames().end(), name) == plannerNames().end()) {
          throw std::invalid_argument("--planners: unknown planner '" + name + "'");
        }
        args.planners.push_back(name);
      }
      if (args.planners.empty()) throw std::invalid_argument("--planners: empty list");
    } else if (arg == "--3d") {
      args.fixed_depth = false;
    } else if (arg == "--expected-distance") {
      args.expected_distance = parseNumber(arg, value());
    } else if (arg == "--admissible-range") {
      args.admissible_range = parseNumber(arg, value());
    } else if (arg == "--narrow-passage-bias") {
      args.narrow_passage_bias = parseNumber(arg, value());
      if (!(*args.narrow_passage_bias >= 0.0 && *args.narrow_passage_bias <= 1.0)) {
        throw std::invalid_argument("--narrow-passage-bias: expected a number in [0, 1]");
      }
    } else if (arg == "--max-climb-angle") {
      args.max_climb_angle = parseNumber(arg, value());
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
  if (files.empty() || files.size() % 2 != 0) {
    throw std::invalid_argument("expected pairs SCENARIO.yaml MAP.bt");
  }
  for (std::size_t i = 0; i < files.size(); i += 2)
    args.worlds.emplace_back(files[i], files[i + 1]);
  return args;
}

std::string formatPoint(const Eigen::Vector3d& p) {
  return formatNumber(p.x(), 1) + ", " + formatNumber(p.y(), 1) + ", " + formatNumber(p.z(), 1);
}

struct RunRecord {
  std::string planner;
  int run = 0;
  double first_solution = std::numeric_limits<double>::infinity();  ///< s; inf: none
  std::vector<double> cost_at;                                      ///< per checkpoint
  double final_length = std::numeric_limits<double>::infinity();    ///< m, to the goal point
  double iterations = 0;
};

/// The best exact solution posted so far: its cost and length measured to the goal point.
std::pair<double, double> postedSolution(const ob::ProblemDefinition& pdef,
                                         const QueryProblem& problem) {
  const double none = std::numeric_limits<double>::infinity();
  if (!pdef.hasExactSolution()) return {none, none};
  auto* path = pdef.getSolutionPath()->as<og::PathGeometric>();
  const auto& states = path->getStates();
  const std::vector<const ob::State*> view(states.begin(), states.end());
  double length = (problem.goal - statePosition(states.back())).norm();
  for (std::size_t i = 1; i < states.size(); ++i) {
    length += (statePosition(states[i]) - statePosition(states[i - 1])).norm();
  }
  return {problem.costToGoal(view), length};
}

RunRecord runOnce(const std::string& name, int run, const QueryProblem& problem,
                  const PlannerSettings& settings, const std::vector<double>& checkpoints) {
  RunRecord record;
  record.planner = name;
  record.run = run;
  const ob::ProblemDefinitionPtr pdef = problem.makeProblemDefinition();
  const ob::PlannerPtr planner = makePlanner(name, problem, settings);
  planner->setProblemDefinition(pdef);
  planner->setup();
  auto* online = dynamic_cast<OnlineRRTstar*>(planner.get());

  double elapsed = 0.0;  // s spent inside solve()
  Clock::time_point slice_start;
  // OMPL's planners report each new best solution; OnlineRRTstar is stopped at its first.
  pdef->setIntermediateSolutionCallback(
      [&](const ob::Planner*, const std::vector<const ob::State*>&, const ob::Cost&) {
        if (std::isinf(record.first_solution)) {
          record.first_solution = elapsed + secondsSince(slice_start);
        }
      });
  auto solveUntil = [&](double until, const std::function<bool()>& stop_early) {
    if (until <= elapsed) return;
    slice_start = Clock::now();
    const auto deadline = slice_start + std::chrono::duration_cast<Clock::duration>(
                                            std::chrono::duration<double>(until - elapsed));
    planner->solve(ob::PlannerTerminationCondition(
        [&] { return Clock::now() >= deadline || (stop_early && stop_early()); }));
    elapsed += secondsSince(slice_start);
  };
  for (double checkpoint : checkpoints) {
    if (online != nullptr && std::isinf(record.first_solution)) {
      solveUntil(checkpoint, [online] { return online->bestSolution() != nullptr; });
      if (online->bestSolution() != nullptr) record.first_solution = elapsed;
    }
    solveUntil(checkpoint, nullptr);
    const auto [cost, length] = postedSolution(*pdef, problem);
    record.cost_at.push_back(cost);
    record.final_length = length;
  }
  if (online != nullptr) {
    record.iterations = static_cast<double>(online->iterations());
  } else if (auto* rrt = dynamic_cast<og::RRTstar*>(planner.get())) {
    record.iterations = rrt->numIterations();
  } else if (auto* bit = dynamic_cast<og::BITstar*>(planner.get())) {
    record.iterations = bit->numIterations();
  }
  return record;
}

struct QueryReport {
  std::string world, query, header;
  std::vector<RunRecord> runs;
};

std::string summaryTable(const QueryReport& report, const std::vector<std::string>& planners,
                         const std::vector<double>& checkpoints) {
  std::ostringstream out;
  out << "| planner | success | first solution median / p90 (ms) |";
  for (double c : checkpoints) out << " cost @" << formatNumber(c, 1) << " s (n) |";
  out << " length @" << formatNumber(checkpoints.back(), 1)
      << " s (m) | iterations |\n|---|---:|---:|";
  for (std::size_t i = 0; i < checkpoints.size(); ++i) out << "---:|";
  out << "---:|---:|\n";
  for (const std::string& planner : planners) {
    std::vector<double> first, lengths, iterations;
    std::vector<std::vector<double>> costs(checkpoints.size());
    int runs = 0, successes = 0;
    for (const RunRecord& r : report.runs) {
      if (r.planner != planner) continue;
      ++runs;
      first.push_back(r.first_solution);
      successes += std::isfinite(r.cost_at.back()) ? 1 : 0;
      iterations.push_back(r.iterations);
      if (std::isfinite(r.final_length)) lengths.push_back(r.final_length);
      for (std::size_t c = 0; c < checkpoints.size(); ++c) {
        if (std::isfinite(r.cost_at[c])) costs[c].push_back(r.cost_at[c]);
      }
    }
    out << "| " << planner << " | " << successes << "/" << runs << " | "
        << formatNumber(1e3 * percentile(first, 0.5), 1, "none") << " / "
        << formatNumber(1e3 * percentile(first, 0.9), 1, "none") << " |";
    for (const auto& c : costs) {
      out << " " << formatNumber(percentile(c, 0.5), 1) << " (" << c.size() << ") |";
    }
    out << " " << formatNumber(percentile(lengths, 0.5), 1) << " | "
        << formatNumber(percentile(iterations, 0.5), 0) << " |\n";
  }
  return out.str();
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  try {
    args = parseArgs(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "planner_bench: " << e.what() << " (--help for usage)\n";
    return 2;
  }
  ompl::RNG::setSeed(args.seed);  // before any planner exists, or OMPL ignores it
  ompl::msg::setLogLevel(ompl::msg::LOG_ERROR);
  PlannerSettings settings = PlannerSettings::componentDefaults();
  settings.fixed_depth = args.fixed_depth;
  settings.cost.expected_distance = args.expected_distance;
  settings.cost.admissible_range = args.admissible_range;
  if (args.narrow_passage_bias) settings.narrow_passage_bias = *args.narrow_passage_bias;
  if (args.max_climb_angle) settings.clearance.max_climb_angle = *args.max_climb_angle;
  std::vector<double> checkpoints;
  for (double c : {0.1, 0.5}) {
    if (c < args.budget) checkpoints.push_back(c);
  }
  checkpoints.push_back(args.budget);

  const std::string started = timestamp();
  const std::string load_before = machineNote();
  const auto wall = Clock::now();
  std::ostringstream md, csv;
  csv << "world,query,planner,run,first_solution_s";
  for (double c : checkpoints) csv << ",cost_at_" << formatNumber(c, 1) << "s";
  csv << ",length_m,iterations\n";
  try {
    for (const auto& [scenario_path, map_path] : args.worlds) {
      const BenchScenario scenario = readScenario(scenario_path);
      const WorldMap map = loadWorldMap(map_path, settings.max_distance);
      std::cout << "== " << scenario.name << ": map " << map_path << " ("
                << map.tree->getResolution() << " m, distance field " << std::fixed
                << std::setprecision(2) << map.build_seconds << " s)\n";
      std::size_t query_count = args.first_query_only ? 1 : scenario.queries.size();
      for (std::size_t q = 0; q < query_count; ++q) {
        const BenchQuery& query = scenario.queries[q];
        const QueryProblem problem = makeQueryProblem(map, query, settings, scenario.seabed_depth);
        QueryReport report;
        report.world = scenario.name;
        report.query = query.name;
        std::ostringstream header;
        header << "### " << scenario.name << " / " << query.name << "\n\nstart ("
               << formatPoint(problem.start) << ") → goal (" << formatPoint(problem.goal)
               << "), tolerance " << query.tolerance << " m, straight line "
               << formatNumber((problem.goal - problem.start).norm(), 1) << " m";
        // Path-length reference on the same map and clearance: cost >= length (Eq. 1 >= 0).
        OracleOptions oracle_options;
        oracle_options.clearance = settings.clearance.clearance();
        oracle_options.grid = map.tree->getResolution();
        oracle_options.fixed_depth = problem.fixed_depth;
        try {
          const ShortestPathOracle oracle(*map.tree, oracle_options);
          const OraclePath shortest = oracle.shortestPath(problem.start, problem.goal);
          header << ", oracle shortest path "
                 << (shortest.found ? formatNumber(shortest.length, 1) + " m" : "none");
        } catch (const OracleError& e) {
          header << ", oracle: " << e.what();
        }
        const double start_clearance = map.field->distance(problem.start);
        const double goal_clearance = map.field->distance(problem.goal);
        header << ", clearance at start " << formatNumber(start_clearance, 2) << " m, at goal "
               << formatNumber(goal_clearance, 2) << " m\n";
        report.header = header.str();
        std::cout << report.header << std::flush;
        ompl::base::ScopedState<> start_state(problem.si);
        problem.setPosition(start_state.get(), problem.start);
        if (!problem.si->isValid(start_state.get())) {
          const std::string note = "start is not valid at clearance " +
                                   formatNumber(settings.clearance.clearance(), 2) +
                                   " m: query skipped\n";
          std::cout << note;
          md << report.header << "\n" << note << "\n";
          continue;
        }
        for (int run = 0; run < args.runs; ++run) {
          for (const std::string& planner : args.planners) {
            report.runs.push_back(runOnce(planner, run, problem, settings, checkpoints));
            const RunRecord& r = report.runs.back();
            csv << scenario.name << "," << query.name << "," << planner << "," << run << ","
                << r.first_solution;
            for (double c : r.cost_at) csv << "," << c;
            csv << "," << r.final_length << "," << r.iterations << "\n";
          }
          if ((run + 1) % 10 == 0 || run + 1 == args.runs) {
            std::cout << "  " << (run + 1) << "/" << args.runs << " runs\n" << std::flush;
          }
        }
        const std::string table = summaryTable(report, args.planners, checkpoints);
        std::cout << "\n" << table << "\n" << std::flush;
        md << report.header << "\n" << table << "\n";
      }
    }
  } catch (const std::exception& e) {
    std::cerr << "planner_bench: " << e.what() << "\n";
    return 1;
  }

  std::ostringstream document;
  document << "# Planner benchmark " << started << "\n\n"
           << "Planners on the worlds' fully known static maps, " << args.runs
           << " runs per planner and query (interleaved), " << args.budget << " s per run, OMPL "
           << OMPL_MAJOR_VERSION << "." << OMPL_MINOR_VERSION << "." << OMPL_PATCH_VERSION
           << ". Settings: " << settings.describe() << ". Machine: " << load_before
           << " at the start, " << machineNote()
           << " at the end (shared machine: other builds ran; timings move with the load). "
           << "Wall time " << formatNumber(secondsSince(wall), 0) << " s.\n\n"
           << "First solution: median / p90 over all runs, a run without a solution counting "
              "as slower than the budget (`none` = the percentile has no solution). Cost: Eq. "
              "(1)-weighted length to the goal point, median over the runs with a solution "
              "then (n = how many). Oracle: shortest path length at the same clearance on "
              "the same map (a lower bound of the cost).\n\n"
           << md.str();
  std::cout << "\n" << document.str().substr(0, document.str().find("\n\n")) << "\n";
  if (!args.out.empty()) {
    std::ofstream(args.out) << document.str();
    std::string csv_path = args.out;
    const auto dot = csv_path.rfind(".md");
    csv_path = (dot == std::string::npos ? csv_path : csv_path.substr(0, dot)) + ".csv";
    std::ofstream(csv_path) << csv.str();
    std::cout << "results: " << args.out << ", " << csv_path << "\n";
  }
  return 0;
}
