// Pull benchmark (not a test): `auv recon pull`'s puller against the recorder component in
// another process (`auv run recorder`, so `install/setup.bash` sourced), over loopback, beside
// rsync of the same files from an rsync daemon on 127.0.0.1 measured in the same run; and the
// resume overhead (bytes received after an interruption / bytes missing). Vendor pairings on DDS
// domains 5 and 6 (test/README.md).
//
//   pull_bench [--files 4] [--file-mb 32] [--runs 3] [--in-flight 8] [--chunk-bytes 1048576]
//              [--root <recordings folder to use instead of random files>] [--out <results.md>]
//              [--pairs cc,ff,cf,fc]  (vehicle vendor, shore vendor: c Cyclone DDS, f Fast DDS)
#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>
#include <thread>
#include <vector>

#include "auv/interfaces/executor.h"
#include "auv/recon/transfer/puller.h"

namespace fs = std::filesystem;
using auv::interfaces::Vendor;
using Clock = std::chrono::steady_clock;

namespace {

struct Options {
  int files = 4;
  int file_mb = 32;
  int runs = 3;
  int in_flight = 8;
  uint32_t chunk_bytes = 1u << 20;
  std::string root;  // empty: random files
  std::string out = "pull_bench_results.md";
  std::string pairs = "cc,ff,cf,fc";  // vehicle/shore vendor pairings (c: Cyclone, f: Fast DDS)
};

pid_t spawn(const std::vector<std::string>& argv) {
  const pid_t pid = fork();
  if (pid == 0) {
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execvp(args[0], args.data());
    _exit(127);
  }
  return pid;
}

/// The vehicle: the recorder component as a deployment runs it, `auv run recorder`, on
/// `vendor` and `domain` (the variables `auv` reads).
pid_t spawnVehicle(const fs::path& root, Vendor vendor, int domain, uint32_t max_chunk) {
  const pid_t pid = fork();
  if (pid == 0) {
    setenv("AUV_DDS", auv::interfaces::toString(vendor).c_str(), 1);
    setenv("AUV_DOMAIN_ID", std::to_string(domain).c_str(), 1);
    const std::vector<std::string> argv = {"auv",
                                           "run",
                                           "recorder",
                                           "-p",
                                           "root:=" + root.string(),
                                           "-p",
                                           "vehicle_name:=bench",
                                           "-p",
                                           "max_chunk_bytes:=" + std::to_string(max_chunk)};
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execvp(args[0], args.data());
    _exit(127);
  }
  return pid;
}

void stop(pid_t pid) {
  kill(pid, SIGTERM);
  int status = 0;
  waitpid(pid, &status, 0);
}

int freePort() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address));
  socklen_t length = sizeof(address);
  getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length);
  const int port = ntohs(address.sin_port);
  close(fd);
  return port;
}

bool canConnect(int port) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(port);
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const bool ok = connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) == 0;
  close(fd);
  return ok;
}

uint64_t folderBytes(const fs::path& folder) {
  uint64_t total = 0;
  for (const auto& entry : fs::recursive_directory_iterator(folder)) {
    if (entry.is_regular_file()) total += entry.file_size();
  }
  return total;
}

/// CPU seconds (user + system, all threads) a process used so far: where the time goes.
double cpuSeconds(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
  const size_t end_of_name = text.rfind(')');
  if (end_of_name == std::string::npos) return 0;
  std::istringstream fields(text.substr(end_of_name + 2));
  std::string field;
  double utime = 0, stime = 0;
  for (int i = 3; i <= 15 && fields >> field; ++i) {  // fields 14 and 15: utime, stime
    if (i == 14) utime = std::stod(field);
    if (i == 15) stime = std::stod(field);
  }
  return (utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

struct PullRun {
  double seconds = 0;
  uint64_t bytes = 0;
  auv::recon::transfer::PullStats stats;
  double shore_cpu_s = 0, vehicle_cpu_s = 0;  // CPU time of each process during the pull
};

/// One pull into a fresh survey; the clock starts once the vehicle is matched.
PullRun pull(Vendor shore_vendor, int domain, const fs::path& survey, const Options& o,
             pid_t vehicle, double stop_fraction = 0) {
  auv::interfaces::Node node("bench_shore", auv::interfaces::nodeOptions(shore_vendor, domain));
  auv::recon::transfer::PullOptions options;
  options.vehicle = "bench";
  options.survey = survey;
  options.in_flight = o.in_flight;
  options.chunk_bytes = o.chunk_bytes;
  options.progress_period_s = stop_fraction > 0 ? 0 : 1.0;
  auv::recon::transfer::Puller puller(node, options);
  if (stop_fraction > 0) {
    puller.onProgress([&](const auv::recon::transfer::PullProgress& p) {
      if (p.bytes_total > 0 && p.bytes_done >= stop_fraction * p.bytes_total) puller.stop();
    });
  }
  const auto deadline = Clock::now() + std::chrono::seconds(60);
  while (!puller.vehicleReady() && Clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  const auto start = Clock::now();
  const double shore_cpu = cpuSeconds(getpid()), vehicle_cpu = cpuSeconds(vehicle);
  const auto result = puller.run();
  PullRun run;
  run.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  run.shore_cpu_s = cpuSeconds(getpid()) - shore_cpu;
  run.vehicle_cpu_s = cpuSeconds(vehicle) - vehicle_cpu;
  run.stats = puller.stats();
  run.bytes = run.stats.bytes_received;
  if (stop_fraction == 0 && result != auv::recon::transfer::PullResult::COMPLETE) {
    throw std::runtime_error("pull did not complete: " + run.stats.lost);
  }
  return run;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  Options o;
  for (size_t i = 0; i + 1 < args.size(); i += 2) {
    if (args[i] == "--files")
      o.files = std::stoi(args[i + 1]);
    else if (args[i] == "--file-mb")
      o.file_mb = std::stoi(args[i + 1]);
    else if (args[i] == "--runs")
      o.runs = std::stoi(args[i + 1]);
    else if (args[i] == "--in-flight")
      o.in_flight = std::stoi(args[i + 1]);
    else if (args[i] == "--chunk-bytes")
      o.chunk_bytes = static_cast<uint32_t>(std::stoul(args[i + 1]));
    else if (args[i] == "--root")
      o.root = args[i + 1];
    else if (args[i] == "--out")
      o.out = args[i + 1];
    else if (args[i] == "--pairs")
      o.pairs = args[i + 1];
    else {
      std::cerr << "pull_bench: unknown option " << args[i] << "\n";
      return 2;
    }
  }
  const fs::path work = fs::temp_directory_path() / ("auv_pull_bench_" + std::to_string(getpid()));
  fs::create_directories(work);
  fs::path root = o.root.empty() ? work / "recordings" : fs::path(o.root);
  if (o.root.empty()) {
    // Incompressible, like encoded video: random bytes.
    std::mt19937_64 generator(42);
    for (int f = 0; f < o.files; ++f) {
      const std::string camera = "cam" + std::to_string(f);
      fs::create_directories(root / camera);
      std::ofstream out(root / camera / (camera + "_0001.mp4"), std::ios::binary);
      std::vector<uint64_t> block(1 << 17);
      for (int mb = 0; mb < o.file_mb; ++mb) {
        for (auto& v : block) v = generator();
        out.write(reinterpret_cast<const char*>(block.data()), 1 << 20);
      }
      std::ofstream(root / camera / (camera + "_0001.mp4.frames.csv"))
          << "frame,camera_time_s,sim_time_s\n0,0.0,0.0\n";
    }
  }
  root = fs::canonical(root);
  const uint64_t total = folderBytes(root);

  // rsync daemon on 127.0.0.1 with a temporary configuration, on a free port.
  const int port = freePort();
  const fs::path conf = work / "rsyncd.conf";
  std::ofstream(conf) << "use chroot = no\npid file = " << (work / "rsyncd.pid").string()
                      << "\n[rec]\npath = " << root.string() << "\nread only = yes\n";
  const pid_t rsyncd = spawn({"rsync", "--daemon", "--no-detach", "--config=" + conf.string(),
                              "--port=" + std::to_string(port), "--address=127.0.0.1",
                              "--log-file=" + (work / "rsyncd.log").string()});
  for (int i = 0; i < 500 && !canConnect(port); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  auto rsyncOnce = [&]() {
    const fs::path dest = work / "rsync_dest";
    fs::remove_all(dest);
    const std::string command = "rsync -a --whole-file rsync://127.0.0.1:" + std::to_string(port) +
                                "/rec/ " + dest.string();
    const auto start = Clock::now();
    if (std::system(command.c_str()) != 0) throw std::runtime_error("rsync failed: " + command);
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    if (folderBytes(dest) != total) throw std::runtime_error("rsync copied a different size");
    return seconds;
  };

  struct Pair {
    Vendor vehicle, shore;
    int domain;
  };
  std::vector<Pair> pairs;
  {
    std::istringstream list(o.pairs);
    std::string code;
    while (std::getline(list, code, ',')) {
      const auto vendor = [](char c) { return c == 'f' ? Vendor::FASTDDS : Vendor::CYCLONEDDS; };
      if (code.size() != 2 || code.find_first_not_of("cf") != std::string::npos) {
        std::cerr << "pull_bench: --pairs: '" << code << "' is not one of cc, ff, cf, fc\n";
        return 2;
      }
      // Domain 5 when the vehicle is on Cyclone, 6 on Fast DDS (test/README.md).
      pairs.push_back({vendor(code[0]), vendor(code[1]), code[0] == 'c' ? 5 : 6});
    }
  }
  std::ostringstream table;
  char host[256] = {0};
  gethostname(host, sizeof(host) - 1);
  table << "# Pull benchmark (`reconstruction/bench/pull_bench`)\n\n"
        << "Host " << host << ", " << std::thread::hardware_concurrency() << " cores; "
        << total / 1e6 << " MB in " << o.files << " recordings ("
        << (o.root.empty() ? "random bytes" : o.root) << "), loopback, in-flight " << o.in_flight
        << ", chunk " << o.chunk_bytes << " B; median of " << o.runs
        << " runs, rsync (daemon on 127.0.0.1, `-a --whole-file`) "
        << "interleaved with the pulls in the same run.\n\n"
        << "| vehicle → shore | pull MB/s | rsync MB/s | pull ÷ rsync | resume overhead (received "
           "÷ missing) | repeats, corrupted |\n"
        << "|---|---|---|---|---|---|\n";
  for (const Pair& pair : pairs) {
    const pid_t vehicle = spawnVehicle(root, pair.vehicle, pair.domain, o.chunk_bytes);
    // Untimed warm-up: the recorder has catalogued (hashed) every file and is discovered.
    fs::remove_all(work / "survey");
    pull(pair.shore, pair.domain, work / "survey", o, vehicle);
    std::vector<double> pull_rates, rsync_rates;
    size_t repeats = 0, corrupted = 0;
    for (int r = 0; r < o.runs; ++r) {
      rsync_rates.push_back(total / rsyncOnce() / 1e6);
      const fs::path survey = work / "survey";
      fs::remove_all(survey);
      const PullRun run = pull(pair.shore, pair.domain, survey, o, vehicle);
      if (run.bytes != total) throw std::runtime_error("pull received a different size");
      pull_rates.push_back(total / run.seconds / 1e6);
      std::cerr << "  run " << r + 1 << ": " << auv::interfaces::toString(pair.vehicle) << " -> "
                << auv::interfaces::toString(pair.shore) << " pull " << pull_rates.back()
                << " MB/s (" << run.stats.requests_timed_out << " repeats; " << run.seconds
                << " s, CPU shore " << run.shore_cpu_s << " s, vehicle " << run.vehicle_cpu_s
                << " s), rsync " << rsync_rates.back() << " MB/s\n";
      repeats += run.stats.requests_timed_out;
      corrupted += run.stats.chunks_corrupted;
    }
    // Resume: interrupted at 40%, then pulled again.
    const fs::path survey = work / "survey";
    fs::remove_all(survey);
    pull(pair.shore, pair.domain, survey, o, vehicle, 0.4);
    const PullRun resumed = pull(pair.shore, pair.domain, survey, o, vehicle);
    const double overhead =
        static_cast<double>(resumed.stats.bytes_received) / resumed.stats.bytes_missing;
    stop(vehicle);
    const double p = median(pull_rates), s = median(rsync_rates);
    char row[512];
    std::snprintf(
        row, sizeof(row), "| %s → %s | %.0f | %.0f | %.2f | %.4f (%.1f of %.1f MB) | %zu, %zu |\n",
        auv::interfaces::toString(pair.vehicle).c_str(),
        auv::interfaces::toString(pair.shore).c_str(), p, s, p / s, overhead,
        resumed.stats.bytes_received / 1e6, resumed.stats.bytes_missing / 1e6, repeats, corrupted);
    table << row;
    std::cout << row << std::flush;
  }
  stop(rsyncd);
  std::ofstream(o.out) << table.str();
  std::cout << "\n" << table.str() << "results written to " << o.out << "\n";
  fs::remove_all(work);
  return 0;
}
