// Keyframe selection speed (issue 6 figure: >= 2x real time per camera on one core at
// 2704x2028): for each video, interleaved runs of
//   * the anchor: a plain cv::VideoCapture decode of every frame (same backend, same video),
//   * the keyframe stage on it (decode + analysis + PNG writing), selectVideoKeyframes,
// pinned to one CPU (sched_setaffinity), median of --runs. Prints frames/s and x real time
// (the video's own frame rate) next to the anchor and appends them to
// <results dir>/keyframes_bench_<time>.md. Both wall time and the process's CPU time are
// measured: on a shared machine the CPU time is what one free core would take (the wall time
// is also spent waiting for the core).
//
//   keyframes_bench [--runs 3] [--cpu 0] [--analysis-width 960] [--results-dir bench_results]
//                   video.mp4...
#include <sched.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include "auv/recon/keyframes/video.h"

namespace fs = std::filesystem;
using namespace auv::recon::keyframes;

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

/// CPU seconds used by this process so far (all threads).
double cpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + t.tv_nsec * 1e-9;
}

struct Decode {
  int frames = 0;
  double seconds = 0, cpu = 0;
};

Decode decodeOnly(const fs::path& video) {
  const auto start = std::chrono::steady_clock::now();
  const double cpu = cpuSeconds();
  cv::VideoCapture capture(video.string(), cv::CAP_FFMPEG);
  cv::Mat frame;
  Decode d;
  while (capture.read(frame)) ++d.frames;
  d.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  d.cpu = cpuSeconds() - cpu;
  return d;
}

std::string timestamp() {
  char text[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(text, sizeof(text), "%Y%m%d_%H%M%S", std::localtime(&now));
  return text;
}

}  // namespace

int main(int argc, char** argv) {
  int runs = 3, cpu = 0;
  fs::path results_dir = "bench_results";
  KeyframeOptions options;
  std::vector<fs::path> videos;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::cerr << arg << ": missing value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    if (arg == "--runs") {
      runs = std::stoi(value());
    } else if (arg == "--cpu") {
      cpu = std::stoi(value());
    } else if (arg == "--analysis-width") {
      options.analysis_width = std::stoi(value());
    } else if (arg == "--results-dir") {
      results_dir = value();
    } else if (arg == "--help" || arg == "-h") {
      std::cout << "usage: keyframes_bench [--runs N] [--cpu K] [--analysis-width PX] "
                   "[--results-dir DIR] video...\n";
      return 0;
    } else if (arg.rfind("--", 0) == 0) {
      std::cerr << "unknown option " << arg << "\n";
      return 2;
    } else {
      videos.emplace_back(arg);
    }
  }
  if (videos.empty() || runs < 1) {
    std::cerr << "usage: keyframes_bench [--runs N] [--cpu K] video... (see bench/README.md)\n";
    return 2;
  }
  // One core: the goal is per camera on one core (the other cameras get the other cores).
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  if (sched_setaffinity(0, sizeof(set), &set) != 0) {
    std::cerr << "cannot pin to CPU " << cpu << "\n";
    return 1;
  }
  cv::setNumThreads(1);

  std::ostringstream table;
  table << "| video | size | frames | video fps | decode only, CPU: frames/s (x real time) | "
           "keyframes stage, CPU: frames/s (x real time) | stage / decode | wall: decode, "
           "stage frames/s | keyframes |\n"
        << "|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& video : videos) {
    cv::VideoCapture probe(video.string(), cv::CAP_FFMPEG);
    if (!probe.isOpened()) {
      std::cerr << video << ": cannot open\n";
      return 1;
    }
    const double fps = probe.get(cv::CAP_PROP_FPS);
    const int width = static_cast<int>(probe.get(cv::CAP_PROP_FRAME_WIDTH));
    const int height = static_cast<int>(probe.get(cv::CAP_PROP_FRAME_HEIGHT));
    probe.release();
    std::vector<double> decode_s, stage_s, decode_cpu, stage_cpu;
    int frames = 0;
    size_t keyframes = 0;
    const fs::path out =
        fs::temp_directory_path() / ("keyframes_bench_" + std::to_string(getpid()));
    for (int r = 0; r < runs; ++r) {
      const Decode d = decodeOnly(video);
      decode_s.push_back(d.seconds);
      decode_cpu.push_back(d.cpu);
      frames = d.frames;
      fs::remove_all(out);
      fs::create_directories(out);
      VideoOptions video_options;
      video_options.keep_damaged = true;  // a benchmark video without sidecar: container count
      const double cpu = cpuSeconds();
      const VideoKeyframes k = selectVideoKeyframes(video, out, options, video_options);
      stage_cpu.push_back(cpuSeconds() - cpu);
      stage_s.push_back(k.seconds);
      keyframes = k.keyframes.size();
      std::cerr << video.filename().string() << " run " << r + 1 << ": decode " << d.seconds
                << " s (CPU " << d.cpu << " s), stage " << k.seconds << " s (CPU "
                << stage_cpu.back() << " s), " << keyframes << " keyframes, " << k.rejected.size()
                << " refused\n";
    }
    fs::remove_all(out);
    const double decode = median(decode_cpu), stage = median(stage_cpu);
    const double duration = fps > 0 ? frames / fps : 0;
    char row[512];
    std::snprintf(row, sizeof(row),
                  "| %s | %dx%d | %d | %.0f | %.1f (%.2fx) | %.1f (%.2fx) | %.2f | %.1f, %.1f | "
                  "%zu |\n",
                  video.filename().string().c_str(), width, height, frames, fps, frames / decode,
                  duration / decode, frames / stage, duration / stage, stage / decode,
                  frames / median(decode_s), frames / median(stage_s), keyframes);
    table << row;
    std::cout << row << std::flush;
  }
  std::ostringstream report;
  char host[256] = {0};
  gethostname(host, sizeof(host) - 1);
  report << "# keyframes_bench " << timestamp() << "\n\n"
         << "Pinned to CPU " << cpu << ", cv::setNumThreads(1), median of " << runs
         << " interleaved runs; analysis_width " << options.analysis_width
         << " px; load average at the end: ";
  std::ifstream load("/proc/loadavg");
  std::string load_text;
  std::getline(load, load_text);
  report << load_text << " (" << host << ").\n\n" << table.str();
  fs::create_directories(results_dir);
  const fs::path file = results_dir / ("keyframes_bench_" + timestamp() + ".md");
  std::ofstream(file) << report.str();
  std::cout << "results: " << file.string() << std::endl;
  return 0;
}
