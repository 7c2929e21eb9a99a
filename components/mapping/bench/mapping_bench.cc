// Mapping benchmark (not a test): beams/s and points/s inserted through MapBuilder (change
// tracking on, as in the component) and through the mapping component on real DDS, each beside
// raw octomap::OcTree::insertPointCloud on the same measurements in the same run, and the
// ratios (issue 4 goal: >= 0.9x). Stream and scene: bench_stream.h; component runs:
// component_bench.h; how to read the figures: README.md, "Benchmark".
//
//   mapping_bench [--beams 200000] [--swaths 2000] [--points 256] [--resolution 0.5]
//                 [--swath-shape canyon|multibeam] [--rows 4]
//                 [--odometry-rate 10] [--seed 1] [--vendors fastdds,cyclonedds]
//                 [--modes inprocess,child,cross] [--domain 86] [--qos bulk_transfer]
//                 [--beam-window 200] [--cloud-window 64] [--pin] [-p name:=value]...
//                 [--out results.md]
//
// --modes: `inprocess` = the component in this process (own node and participant, spun by the
// main thread; a feeder thread publishes), `child` = the component in a child process as
// `auv run mapping` hosts it, `cross` = the same fed from the other vendor; `none` = library
// only. Domains: --domain + 0..3 (fastdds in process, fastdds child, cyclonedds in process,
// cyclonedds child; test/README.md). -p: component parameters.
// --pin: raw, library and the component's executor thread on CPU 1, everything else on CPU 0
// (only useful on an otherwise idle machine: with other load on CPU 0 the feeder starves).
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "bench_stream.h"
#include "component_bench.h"

namespace {

using namespace auv::mapping;
using namespace auv::mapping::bench;
using Clock = std::chrono::steady_clock;

struct Args {
  StreamOptions stream;
  double resolution = 0.5;
  std::vector<std::string> vendors{"fastdds", "cyclonedds"};
  std::vector<std::string> modes{"inprocess", "child", "cross"};
  int domain = 86;
  std::string qos = "bulk_transfer";
  std::size_t beam_window = ComponentRun().beam_window;
  std::size_t cloud_window = ComponentRun().cloud_window;
  std::vector<std::string> parameters;
  std::string out;
  bool pin = false;
  bool serve = false;  // child: host the component
  std::string serve_vendor = "cyclonedds";
  int progress_fd = -1;
};

std::vector<std::string> splitList(const std::string& value) {
  std::vector<std::string> out;
  std::stringstream in(value);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

constexpr const char* kUsage =
    "usage: mapping_bench [--beams 200000] [--swaths 2000] [--points 256] [--resolution 0.5]\n"
    "         [--swath-shape canyon|multibeam] [--rows 4]\n"
    "         [--odometry-rate 10] [--seed 1] [--vendors fastdds,cyclonedds]\n"
    "         [--modes inprocess,child,cross|none] [--domain 86] [--qos bulk_transfer|default]\n"
    "         [--beam-window 200] [--cloud-window 64] [--pin] [-p name:=value]... [--out f.md]\n"
    "Beams/s and points/s through MapBuilder and the mapping component (in this process,\n"
    "in a child process, in a child fed from the other vendor) vs raw\n"
    "OcTree::insertPointCloud on the same data; components/mapping/README.md, Benchmark.\n";

Args parseArgs(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string key = argv[i];
    if (key == "-h" || key == "--help") {
      std::cout << kUsage;
      std::exit(0);
    }
    if (key == "--serve" || key == "--pin" || key == "--no-pin") {
      if (key == "--serve") a.serve = true;
      if (key != "--serve") a.pin = key == "--pin";
      continue;
    }
    if (i + 1 >= argc) throw std::invalid_argument("missing value after " + key);
    const std::string value = argv[++i];
    if (key == "--beams")
      a.stream.beams = std::stoul(value);
    else if (key == "--swaths")
      a.stream.swaths = std::stoul(value);
    else if (key == "--points")
      a.stream.points = std::stoul(value);
    else if (key == "--swath-shape")
      a.stream.swath_shape = value;
    else if (key == "--rows")
      a.stream.rows = std::stoul(value);
    else if (key == "--odometry-rate")
      a.stream.odometry_rate = std::stod(value);
    else if (key == "--seed")
      a.stream.seed = static_cast<unsigned>(std::stoul(value));
    else if (key == "--resolution")
      a.resolution = std::stod(value);
    else if (key == "--vendors" || key == "--vendor") {
      a.vendors = splitList(value);
      a.serve_vendor = value;
    } else if (key == "--modes")
      a.modes = value == "none" ? std::vector<std::string>{} : splitList(value);
    else if (key == "--domain")
      a.domain = std::stoi(value);
    else if (key == "--progress-fd")
      a.progress_fd = std::stoi(value);
    else if (key == "--qos")
      a.qos = value == "default" ? "" : value;
    else if (key == "--beam-window")
      a.beam_window = std::stoul(value);
    else if (key == "--cloud-window")
      a.cloud_window = std::stoul(value);
    else if (key == "-p")
      a.parameters.push_back(value);
    else if (key == "--out")
      a.out = value;
    else
      throw std::invalid_argument("unknown option " + key);
  }
  for (const auto& m : a.modes) {
    if (m != "inprocess" && m != "child" && m != "cross")
      throw std::invalid_argument("unknown mode " + m);
  }
  return a;
}

double threadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// One timed insertion of the whole input on this thread.
struct Timed {
  double seconds = 0.0;
  double cpu_seconds = 0.0;
  std::string map_ot;  // AbstractOcTree::write (log-odds)
  std::string map_bt;  // writeBinaryConst (maximum likelihood)
};

template <class Tree>
void writeMaps(const Tree& tree, Timed& timed) {
  std::ostringstream ot, bt;
  tree.write(ot);
  tree.writeBinaryConst(bt);
  timed.map_ot = ot.str();
  timed.map_bt = bt.str();
}

template <class Body>
void time(Timed& timed, Body&& body) {
  const double cpu0 = threadCpuSeconds();
  const auto t0 = Clock::now();
  body();
  timed.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  timed.cpu_seconds = threadCpuSeconds() - cpu0;
}

Timed rawBeams(const Stream& s, double resolution) {
  Timed timed;
  octomap::OcTree tree(resolution);
  octomap::Pointcloud one;
  time(timed, [&] {
    for (std::size_t i = 0; i < s.raw_beam_ends.size(); ++i) {
      one.clear();
      one.push_back(s.raw_beam_ends[i]);
      tree.insertPointCloud(one, s.raw_beam_origins[i], s.beam_max_range);
    }
  });
  writeMaps(tree, timed);
  return timed;
}

Timed libraryBeams(const Stream& s, const MapBuilder::Options& options) {
  Timed timed;
  MapBuilder builder(options);
  builder.enableChangeTracking(true);
  time(timed, [&] {
    for (std::size_t i = 0; i < s.beam_geometry.size(); ++i)
      builder.insertBeam(s.beam_geometry[i], s.beam_world_T_sensor[i]);
  });
  builder.takeDiff();
  writeMaps(builder.tree(), timed);
  return timed;
}

Timed rawClouds(const Stream& s, double resolution) {
  Timed timed;
  octomap::OcTree tree(resolution);
  time(timed, [&] {
    for (std::size_t i = 0; i < s.raw_clouds.size(); ++i) {
      const Eigen::Vector3d& o = s.cloud_origins[i];
      tree.insertPointCloud(s.raw_clouds[i],
                            octomap::point3d(static_cast<float>(o.x()), static_cast<float>(o.y()),
                                             static_cast<float>(o.z())),
                            s.cloud_max_range);
    }
  });
  writeMaps(tree, timed);
  return timed;
}

Timed libraryClouds(const Stream& s, const MapBuilder::Options& options) {
  Timed timed;
  MapBuilder builder(options);
  builder.enableChangeTracking(true);
  time(timed, [&] {
    for (std::size_t i = 0; i < s.cloud_points.size(); ++i)
      builder.insertCloud(s.cloud_points[i], s.cloud_origins[i], s.cloud_max_range);
  });
  builder.takeDiff();
  writeMaps(builder.tree(), timed);
  return timed;
}

std::string fmt(double value, int precision = 0) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(precision) << value;
  return out.str();
}

/// One input kind (beams or points): the library and the component runs, each beside a raw
/// run made just before it (the machine is shared: its load drifts within seconds).
class Table {
 public:
  Table(std::string unit, double count) : unit_(std::move(unit)), count_(count) {}
  void library(const Timed& raw, const Timed& t) {
    library_ot_ = t.map_ot;
    rows_.push_back({"MapBuilder (library)", count_ / t.seconds, 1e6 * t.cpu_seconds / count_, -1.0,
                     t.map_bt == raw.map_bt ? "yes (= raw)" : "NO", "", raw});
  }
  void component(const std::string& what, const Timed& raw, const ComponentResult& r) {
    if (!r.ok) {
      rows_.push_back({what, 0.0, 0.0, 0.0, "", "failed: " + r.error, raw});
      return;
    }
    // How much of the time the executor had work: the rest it waited for input.
    std::string note =
        fmt(r.seconds, 2) + " s, executor busy " + fmt(100.0 * r.executor_cpu_s / r.seconds) + " %";
    if (r.updates > 0) note += ", " + std::to_string(r.updates) + " map updates";
    if (r.dropped > 0) note += ", " + std::to_string(r.dropped) + " dropped";
    if (r.publish_retries > 0) note += ", " + std::to_string(r.publish_retries) + " write retries";
    rows_.push_back({what, r.per_s, 1e6 * r.executor_cpu_s / count_, 1e6 * r.total_cpu_s / count_,
                     r.map_ot == library_ot_ ? "yes (= library)" : "NO", note, raw});
  }
  std::string markdown() const {
    std::ostringstream out;
    out << "| path | " << unit_ << "s/s | raw " << unit_ << "s/s | ratio | CPU µs/" << unit_
        << " | raw CPU µs/" << unit_ << " | CPU ratio | CPU µs/" << unit_
        << " (all threads) | same map | notes |\n"
        << "|---|---:|---:|---:|---:|---:|---:|---:|---|---|\n";
    for (const Row& row : rows_) {
      const double raw_rate = count_ / row.raw.seconds;
      const double raw_us = 1e6 * row.raw.cpu_seconds / count_;
      out << "| " << row.what << " | ";
      if (row.rate <= 0.0) {
        out << "| " << fmt(raw_rate) << " | | | " << fmt(raw_us, 2) << " | | | | " << row.note
            << " |\n";
        continue;
      }
      out << fmt(row.rate) << " | " << fmt(raw_rate) << " | " << fmt(row.rate / raw_rate, 2)
          << " | " << fmt(row.thread_us, 2) << " | " << fmt(raw_us, 2) << " | "
          << fmt(raw_us / row.thread_us, 2) << " | "
          << (row.process_us < 0 ? std::string("-") : fmt(row.process_us, 2)) << " | " << row.same
          << " | " << row.note << " |\n";
    }
    out << "\nraw = OcTree::insertPointCloud on the same data, measured just before the row. "
        << "ratio = " << unit_ << "s/s / raw " << unit_ << "s/s (goal >= 0.9). CPU µs = CPU time "
        << "of the inserting thread (library: the measuring thread, component: its executor "
        << "thread); CPU ratio = raw's / the row's; all threads: component, feeder, map reader "
        << "and the DDS threads of both sides (2 CPUs: at most 2 s per s).\n";
    return out.str();
  }

 private:
  struct Row {
    std::string what;
    double rate;        // per second; 0: failed
    double thread_us;   // CPU per measurement, inserting thread
    double process_us;  // CPU per measurement, all threads of the pipeline; < 0: -
    std::string same;
    std::string note;
    Timed raw;
  };
  std::string unit_;
  double count_;
  std::string library_ot_;
  std::vector<Row> rows_;
};

/// Runs `measure` with this thread on kWorkCpu when pinning (the CPU the component's executor
/// gets), then returns to kOtherCpu.
template <class F>
Timed onWorkCpu(bool pin, F&& measure) {
  if (pin) pinThisThread(kWorkCpu);
  Timed timed = measure();
  if (pin) pinThisThread(kOtherCpu);
  return timed;
}

std::string selfExecutable() {
  char path[4096];
  const ssize_t n = readlink("/proc/self/exe", path, sizeof(path) - 1);
  if (n <= 0) throw std::runtime_error("cannot read /proc/self/exe");
  return std::string(path, static_cast<std::size_t>(n));
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  try {
    args = parseArgs(argc, argv);
    if (args.serve) {
      return serveComponent(auv::interfaces::vendorFromString(args.serve_vendor), args.domain,
                            args.parameters, args.progress_fd, args.pin);
    }
  } catch (const std::exception& e) {
    std::cerr << "mapping_bench: " << e.what() << "\n" << kUsage;
    return 2;
  }
  if (args.pin && (sysconf(_SC_NPROCESSORS_ONLN) < 2 || !pinThisThread(kOtherCpu))) {
    std::cerr << "mapping_bench: cannot pin to CPUs 0 and 1, running unpinned\n";
    args.pin = false;
  }
  MapBuilder::Options options;
  options.resolution = args.resolution;
  const Stream stream = makeStream(args.stream);
  std::vector<std::string> parameters{"resolution:=" + std::to_string(args.resolution)};
  parameters.insert(parameters.end(), args.parameters.begin(), args.parameters.end());

  // Component runs, vendor-major; per vendor one domain in this process, one for a child.
  struct Run {
    std::string name;
    ComponentRun run;
  };
  std::vector<Run> runs;
  for (std::size_t v = 0; v < args.vendors.size(); ++v) {
    for (const std::string mode : {"inprocess", "child", "cross"}) {
      if (std::find(args.modes.begin(), args.modes.end(), mode) == args.modes.end()) continue;
      ComponentRun run;
      run.vendor = auv::interfaces::vendorFromString(args.vendors[v]);
      run.domain = args.domain + static_cast<int>(2 * v) + (mode == "inprocess" ? 0 : 1);
      run.child_process = mode != "inprocess";
      std::string name =
          "component, " + args.vendors[v] + (run.child_process ? ", own process" : ", in process");
      if (mode == "cross") {
        run.feeder_vendor = run.vendor == auv::interfaces::Vendor::FASTDDS
                                ? auv::interfaces::Vendor::CYCLONEDDS
                                : auv::interfaces::Vendor::FASTDDS;
        name += ", fed by " + auv::interfaces::toString(*run.feeder_vendor);
      }
      run.self_executable = selfExecutable();
      run.qos = args.qos;
      run.beam_window = args.beam_window;
      run.cloud_window = args.cloud_window;
      run.pin = args.pin;
      run.parameters = parameters;
      runs.push_back({name, run});
    }
  }

  const double n_beams = static_cast<double>(stream.beams.size());
  Table beams("beam", n_beams);
  const bool pin = args.pin;
  auto raw_beams = [&] {
    return onWorkCpu(pin, [&] { return rawBeams(stream, args.resolution); });
  };
  {
    const Timed raw = raw_beams();
    beams.library(raw, onWorkCpu(pin, [&] { return libraryBeams(stream, options); }));
  }
  for (const Run& r : runs) {
    std::cerr << "mapping_bench: beams through the " << r.name << " ...\n";
    const Timed raw = raw_beams();
    beams.component(r.name, raw, runBeams(stream, r.run));
  }

  const double n_points = static_cast<double>(stream.clouds.size() * stream.points_per_cloud);
  Table points("point", n_points);
  auto raw_clouds = [&] {
    return onWorkCpu(pin, [&] { return rawClouds(stream, args.resolution); });
  };
  {
    const Timed raw = raw_clouds();
    points.library(raw, onWorkCpu(pin, [&] { return libraryClouds(stream, options); }));
  }
  for (const Run& r : runs) {
    std::cerr << "mapping_bench: clouds through the " << r.name << " ...\n";
    const Timed raw = raw_clouds();
    points.component(r.name, raw, runClouds(stream, stream.points_per_cloud, r.run));
  }

  std::ostringstream report;
  report << "# mapping_bench\n\n"
         << "resolution " << args.resolution << " m; " << stream.beams.size()
         << " profiler beams (50 Hz stamps, 200 bins each) with odometry at "
         << args.stream.odometry_rate << " Hz (" << stream.odometry.size() << " samples); "
         << stream.clouds.size() << " " << args.stream.swath_shape << " swaths x "
         << stream.points_per_cloud << " points; seed " << args.stream.seed
         << "; component input QoS " << (args.qos.empty() ? std::string("default") : args.qos)
         << "; feeder window " << args.beam_window << " beams / " << args.cloud_window
         << " clouds; " << sysconf(_SC_NPROCESSORS_ONLN) << " CPUs, "
         << (pin ? "raw, library and the component's executor thread pinned to CPU 1, the rest "
                   "to CPU 0"
                 : "unpinned")
         << "\n\n"
         << "## Beams\n\n"
         << beams.markdown() << "\n## Points (multibeam swaths, one PointCloud per swath)\n\n"
         << points.markdown();
  std::cout << report.str();
  if (!args.out.empty()) {
    std::ofstream file(args.out);
    file << report.str();
    if (!file) {
      std::cerr << "cannot write " << args.out << "\n";
      return 1;
    }
  }
  return 0;
}
