// foxglove_bridge benchmark: what the bridge adds between a DDS publisher and a Foxglove
// client, beside a direct DDS subscriber measured in the same run (the anchor).
//
//   foxglove_bridge_bench [--seconds S] [--out results.json] [--auv /path/to/auv]
//
// Three processes on loopback, domain 158 (test/README.md): this one publishes (Fast DDS) and
// is the Foxglove client (websocketpp); `auv run foxglove_bridge` (Cyclone DDS) forwards; this
// binary again with --direct is a plain serialized DDS reader (Cyclone DDS). Per case:
//  * latency: write -> received, p50 and p99, through the bridge and directly (steady clock,
//    one machine), and the bridge's added latency (the difference per sample);
//  * CPU per MB: CPU seconds of the bridge process and of the direct reader per MB received.
// Cases: state-sized samples (Odometry, ~0.4 kB) at 50 Hz, and a 1352x1014 JPEG
// CompressedImage (the cameras' size) at 10 Hz, both reliable (so sample i is i everywhere).
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "auv/interfaces/graph.h"
#include "auv/interfaces/serialized.h"
#include "auv/msg/all.h"
#include "ws_client.h"

extern char** environ;

pid_t g_bridge = 0;  // the bridge process (main starts it, the cases read its CPU time)

namespace {

using namespace std::chrono_literals;
using auv::foxglove_bridge::test::WsClient;
using nlohmann::json;
namespace ai = auv::interfaces;

constexpr int kDomain = 158;
constexpr int kPort = 18765;

int64_t now() { return std::chrono::steady_clock::now().time_since_epoch().count(); }

// CPU seconds (user + system) of process `pid` from /proc.
double cpuSeconds(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(in)), {});
  std::istringstream fields(text.substr(text.rfind(')') + 2));
  std::string f;
  double ticks = 0;
  for (int i = 3; i <= 15 && fields >> f; ++i)
    if (i >= 14) ticks += std::stod(f);
  return ticks / sysconf(_SC_CLK_TCK);
}

pid_t spawn(const std::vector<std::string>& args) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawnp(&pid, argv[0], nullptr, nullptr, argv.data(), environ) != 0)
    throw std::runtime_error("cannot start " + args[0]);
  return pid;
}

void stopChild(pid_t pid) {
  ::kill(pid, SIGINT);
  int status = 0;
  ::waitpid(pid, &status, 0);
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(
      std::min<double>(v.size() - 1, std::floor(p * (v.size() - 1) + 0.5)))];
}

// --direct TOPIC TYPE FILE: receive times (steady ns, one per line) of every sample of TOPIC.
int directReader(const std::string& topic, const std::string& type_name, const std::string& file) {
  auto participant = ai::createParticipant(ai::Vendor::CYCLONEDDS, {kDomain, "direct"});
  std::mutex mutex;
  std::vector<int64_t> times;
  ai::SerializedSample sample;
  auto reader = participant->createSerializedReader(topic, ai::typeSupportByName(type_name),
                                                    ai::commandQos(), [&](ai::SerializedReader& r) {
                                                      while (r.take(sample)) {
                                                        std::lock_guard<std::mutex> lock(mutex);
                                                        times.push_back(now());
                                                      }
                                                    });
  static std::atomic<bool> stop{false};
  ::signal(SIGINT, [](int) { stop = true; });
  while (!stop) std::this_thread::sleep_for(10ms);
  reader.reset();
  std::ofstream out(file);
  for (int64_t t : times) out << t << "\n";
  return 0;
}

// A 1352x1014 colour frame with texture and gradients (a JPEG of noise or of a flat colour
// would be far from a camera's size), encoded at quality 90.
std::vector<uint8_t> cameraJpeg() {
  cv::Mat image(1014, 1352, CV_8UC3);
  std::mt19937 random(7);
  cv::randu(image, cv::Scalar(0, 0, 0), cv::Scalar(255, 255, 255));
  cv::GaussianBlur(image, image, cv::Size(0, 0), 3.0);
  for (int y = 0; y < image.rows; ++y) image.row(y) += cv::Scalar(40 + y / 10, 60, 30);
  std::vector<uint8_t> jpeg;
  cv::imencode(".jpg", image, jpeg, {cv::IMWRITE_JPEG_QUALITY, 90});
  return jpeg;
}

struct Case {
  std::string name, topic, type;
  double rate_hz;
  std::shared_ptr<void> sample;
  size_t bytes = 0;
};

json runCase(Case& c, double seconds) {
  auto publisher = ai::createParticipant(ai::Vendor::FASTDDS, {kDomain, "bench_publisher"});
  const auto& type = ai::typeSupportByName(c.type);
  auto writer = publisher->createWriter(c.topic, type, ai::commandQos());
  const std::string times_file = "/tmp/auv_foxglove_bench_direct_" + std::to_string(getpid());
  const pid_t direct = spawn({"/proc/self/exe", "--direct", c.topic, c.type, times_file});
  WsClient client("ws://127.0.0.1:" + std::to_string(kPort) + "/");
  if (!client.waitOpen(10s)) throw std::runtime_error("no bridge on port " + std::to_string(kPort));
  if (!client.waitFor([&] { return client.channel(c.topic) >= 0; }, 10s))
    throw std::runtime_error(c.topic + " not advertised");
  client.subscribe(1, static_cast<uint32_t>(client.channel(c.topic)));
  const auto matched = [&] { return writer->matchedReaders() >= 2; };
  for (auto t0 = std::chrono::steady_clock::now();
       !matched() && std::chrono::steady_clock::now() - t0 < 10s;)
    std::this_thread::sleep_for(10ms);
  std::this_thread::sleep_for(1s);  // both readers fully matched (Fast DDS <-> Cyclone)
  const double bridge_cpu0 = cpuSeconds(g_bridge), direct_cpu0 = cpuSeconds(direct);
  const int n = static_cast<int>(seconds * c.rate_hz);
  std::vector<int64_t> written;
  const auto period = std::chrono::nanoseconds(static_cast<int64_t>(1e9 / c.rate_hz));
  auto next = std::chrono::steady_clock::now();
  for (int i = 0; i < n; ++i) {
    std::this_thread::sleep_until(next);
    next += period;
    written.push_back(now());
    writer->write(c.sample.get());
  }
  client.waitFor([&] { return static_cast<int>(client.frames().size()) >= n; }, 10s);
  std::this_thread::sleep_for(500ms);
  const double bridge_cpu = cpuSeconds(g_bridge) - bridge_cpu0;
  const double direct_cpu = cpuSeconds(direct) - direct_cpu0;
  stopChild(direct);
  std::vector<int64_t> direct_times;
  {
    std::ifstream in(times_file);
    for (int64_t t; in >> t;) direct_times.push_back(t);
    std::remove(times_file.c_str());
  }
  const auto bridge_times = client.frameTimes();
  std::vector<double> via_bridge, via_direct, added;
  for (int i = 0; i < n; ++i) {
    const bool b = i < static_cast<int>(bridge_times.size()),
               d = i < static_cast<int>(direct_times.size());
    if (b) via_bridge.push_back((bridge_times[i] - written[i]) / 1e6);
    if (d) via_direct.push_back((direct_times[i] - written[i]) / 1e6);
    if (b && d) added.push_back((bridge_times[i] - direct_times[i]) / 1e6);
  }
  const double mb = static_cast<double>(c.bytes) * n / 1e6;
  json r = {{"case", c.name},
            {"sample_bytes", c.bytes},
            {"rate_hz", c.rate_hz},
            {"samples", n},
            {"received_bridge", bridge_times.size()},
            {"received_direct", direct_times.size()},
            {"latency_ms_bridge_p50", percentile(via_bridge, 0.5)},
            {"latency_ms_bridge_p99", percentile(via_bridge, 0.99)},
            {"latency_ms_direct_p50", percentile(via_direct, 0.5)},
            {"latency_ms_direct_p99", percentile(via_direct, 0.99)},
            {"added_ms_p50", percentile(added, 0.5)},
            {"added_ms_p99", percentile(added, 0.99)},
            {"cpu_s_per_mb_bridge", bridge_cpu / mb},
            {"cpu_s_per_mb_direct", direct_cpu / mb},
            {"mb", mb}};
  std::printf("%-22s %6zu B @ %4.0f Hz, %d samples (bridge got %zu, direct %zu)\n", c.name.c_str(),
              c.bytes, c.rate_hz, n, bridge_times.size(), direct_times.size());
  std::printf(
      "  latency p50/p99  bridge %7.3f / %7.3f ms   direct (anchor) %7.3f / %7.3f ms   added %7.3f "
      "/ %7.3f ms\n",
      r["latency_ms_bridge_p50"].get<double>(), r["latency_ms_bridge_p99"].get<double>(),
      r["latency_ms_direct_p50"].get<double>(), r["latency_ms_direct_p99"].get<double>(),
      r["added_ms_p50"].get<double>(), r["added_ms_p99"].get<double>());
  std::printf("  CPU per MB       bridge %7.4f s          direct (anchor) %7.4f s   (%.1f MB)\n",
              bridge_cpu / mb, direct_cpu / mb, mb);
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    if (argc == 5 && std::string(argv[1]) == "--direct")
      return directReader(argv[2], argv[3], argv[4]);
    double seconds = 5;
    std::string out = "foxglove_bridge_bench.json", auv_exe = "auv";
    for (int i = 1; i + 1 < argc; i += 2) {
      const std::string flag = argv[i];
      if (flag == "--seconds")
        seconds = std::stod(argv[i + 1]);
      else if (flag == "--out")
        out = argv[i + 1];
      else if (flag == "--auv")
        auv_exe = argv[i + 1];
      else
        throw std::invalid_argument("unknown option " + flag);
    }
    ::setenv("AUV_DOMAIN_ID", std::to_string(kDomain).c_str(), 1);
    g_bridge = spawn({auv_exe, "run", "foxglove_bridge", "-p", "port:=" + std::to_string(kPort),
                      "-p", "discovery_period:=0.1"});
    std::this_thread::sleep_for(2s);
    // The bridge's own CPU with nothing to forward (discovery, timers): the floor under the
    // per-MB figures, which include it.
    const double idle0 = cpuSeconds(g_bridge);
    std::this_thread::sleep_for(3s);
    const double idle_percent = (cpuSeconds(g_bridge) - idle0) / 3.0 * 100;
    std::printf("bridge idle: %.1f %% of a core\n", idle_percent);
    std::vector<Case> cases;
    auto odometry = auv::msg::findType("Odometry")->create_sample();
    cases.push_back({"odometry (state)", "/bench/odometry", "Odometry", 50, odometry, 0});
    auto image = std::static_pointer_cast<auv::msg::CompressedImage>(
        auv::msg::findType("CompressedImage")->create_sample());
    image->format("jpeg");
    image->data(cameraJpeg());
    image->header().frame_id("camera_left");
    cases.push_back(
        {"camera 1352x1014 jpeg", "/bench/camera/compressed", "CompressedImage", 10, image, 0});
    json results = {
        {"seconds", seconds}, {"bridge_idle_cpu_percent", idle_percent}, {"cases", json::array()}};
    for (Case& c : cases) {
      // Bytes on the wire: the type's own serialization.
      const auto& type = ai::typeSupportByName(c.type);
      std::unique_ptr<eprosima::fastdds::dds::TopicDataType> tdt(type.make_topic_data_type());
      c.bytes = tdt->getSerializedSizeProvider(c.sample.get())();
      results["cases"].push_back(runCase(c, seconds));
    }
    stopChild(g_bridge);
    std::ofstream(out) << results.dump(2) << "\n";
    std::printf("results: %s\n", out.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "foxglove_bridge_bench: %s\n", e.what());
    if (g_bridge) stopChild(g_bridge);
    return 1;
  }
}
