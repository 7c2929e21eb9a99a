// `auv bag record` throughput on real DDS: a writer in a child process publishes N MiB of
// FileChunkReply samples (reliable, keep all: it waits for its slowest reader) and the
// Recorder writes them into an MCAP file; the anchor, measured in the same run with the same
// samples, is a plain serialized reader that only takes them (a direct subscriber: what the
// middleware alone costs). Prints a table and writes it to --out (bench/README.md, "Recording").
//
//   record_bench [--mib N] [--dir DIR] [--out FILE] [--domain D]
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "auv/bag/dds/recorder.h"
#include "auv/interfaces/serialized.h"
#include "auv/msg/all.h"

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;
using auv::interfaces::Vendor;

struct Row {
  std::string writer, reader;
  size_t size = 0;
  double anchor_mbs = 0, record_mbs = 0;
  uint64_t recorded = 0, lost = 0, sent = 0;
  double file_over_data = 0;
};

/// The writer's side, in a process of its own (`record_bench --publish ...`): publishes
/// `count` samples of `size` random bytes each (made before the clock starts, no two alike,
/// like JPEG frames) once a reader matched, waits for every reader to acknowledge them, and
/// prints the seconds from the first write to the last acknowledgment.
int publishMain(const std::string& vendor, int domain, const std::string& topic, size_t count,
                size_t size) {
  auto participant = auv::interfaces::createParticipant(auv::interfaces::vendorFromString(vendor),
                                                        {domain, "bench_writer"});
  const auto& type = auv::interfaces::typeSupportByName("FileChunkReply");
  auto writer = participant->createWriter(topic, type, auv::interfaces::bulkTransferQos());
  std::vector<auv::msg::FileChunkReply> samples(count);
  std::mt19937 generator(7);
  for (size_t i = 0; i < count; ++i) {
    std::vector<uint8_t> bytes(size);
    for (auto& b : bytes) b = static_cast<uint8_t>(generator());
    samples[i].data(std::move(bytes));
    samples[i].offset(i);
  }
  const auto deadline = Clock::now() + 20s;
  while (writer->matchedReaders() == 0 && Clock::now() < deadline)
    std::this_thread::sleep_for(10ms);
  std::this_thread::sleep_for(500ms);  // matched both ways
  const auto start = Clock::now();
  for (const auto& sample : samples) writer->write(&sample);
  writer->waitForAcknowledgments(300.0);
  std::printf("%.6f\n", std::chrono::duration<double>(Clock::now() - start).count());
  return 0;
}

/// Runs this program's publisher side as a child process; its seconds, or -1.
double publish(const std::string& vendor, int domain, const std::string& topic, size_t count,
               size_t size) {
  const std::string command = "/proc/" + std::to_string(::getpid()) + "/exe --publish " + vendor +
                              " " + std::to_string(domain) + " " + topic + " " +
                              std::to_string(count) + " " + std::to_string(size);
  FILE* pipe = ::popen(command.c_str(), "r");
  if (!pipe) return -1;
  double s = -1;
  if (std::fscanf(pipe, "%lf", &s) != 1) s = -1;
  ::pclose(pipe);
  return s;
}

Row measure(Vendor writer_vendor, Vendor reader_vendor, size_t size, double mib,
            const fs::path& dir, int domain) {
  Row row;
  row.writer = auv::interfaces::toString(writer_vendor);
  row.reader = auv::interfaces::toString(reader_vendor);
  row.size = size;
  // At least 64 messages, so that a row of large ones is not a handful of writes.
  const size_t count = std::max<size_t>(64, static_cast<size_t>(mib * 1048576.0 / size));
  row.sent = count;
  const double megabytes = static_cast<double>(count * size) / 1e6;
  const auto& type = auv::interfaces::typeSupportByName("FileChunkReply");
  {  // anchor: a serialized reader that takes and counts
    auto listener = auv::interfaces::createParticipant(reader_vendor, {domain, "bench_reader"});
    std::atomic<uint64_t> taken{0};
    auv::interfaces::SerializedSample sample;
    auto reader =
        listener->createSerializedReader("/bench/anchor", type, auv::interfaces::bulkTransferQos(),
                                         [&](auv::interfaces::SerializedReader& r) {
                                           while (r.take(sample)) ++taken;
                                         });
    const double s = publish(row.writer, domain, "/bench/anchor", count, size);
    row.anchor_mbs = megabytes / s;
  }
  {  // the recorder
    auv::bag::RecorderOptions options;
    options.output = (dir / ("record_bench_" + std::to_string(::getpid()) + ".mcap")).string();
    options.domain_id = domain;
    options.vendor = row.reader;
    options.topics = {"/bench/record"};
    options.overwrite = true;
    auv::bag::Recorder recorder(options);
    recorder.start();
    const double s = publish(row.writer, domain, "/bench/record", count, size);
    row.record_mbs = megabytes / s;
    recorder.stop();
    const auto stats = recorder.stats();
    for (const auto& topic : stats.topics) {
      row.recorded += topic.messages;
      row.lost += topic.lost;
    }
    row.file_over_data = static_cast<double>(fs::file_size(options.output)) / (megabytes * 1e6);
    fs::remove(options.output);
  }
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 7 && std::string(argv[1]) == "--publish")
    return publishMain(argv[2], std::stoi(argv[3]), argv[4], std::stoull(argv[5]),
                       std::stoull(argv[6]));
  double mib = 64;
  fs::path dir = fs::temp_directory_path();
  std::string out;
  int domain = 24;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string arg = argv[i];
    if (arg == "--mib")
      mib = std::stod(argv[i + 1]);
    else if (arg == "--dir")
      dir = argv[i + 1];
    else if (arg == "--out")
      out = argv[i + 1];
    else if (arg == "--domain")
      domain = std::stoi(argv[i + 1]);
    else {
      std::fprintf(stderr, "usage: record_bench [--mib N] [--dir DIR] [--out FILE] [--domain D]\n");
      return 2;
    }
  }
  std::ostringstream table;
  table << "| writer | recorder | message | sent | recorded | lost | anchor MB/s (direct "
           "subscriber) | record MB/s | record / anchor | file / data |\n"
           "|---|---|---|---|---|---|---|---|---|---|\n";
  for (size_t size : {size_t{1024}, size_t{1} << 20}) {
    for (const auto& [w, r] : {std::pair{Vendor::CYCLONEDDS, Vendor::CYCLONEDDS},
                               std::pair{Vendor::FASTDDS, Vendor::CYCLONEDDS},
                               std::pair{Vendor::FASTDDS, Vendor::FASTDDS}}) {
      const Row row = measure(w, r, size, mib, dir, domain);
      char line[512];
      std::snprintf(
          line, sizeof line, "| %s | %s | %s | %llu | %llu | %llu | %.1f | %.1f | %.2f | %.3f |\n",
          row.writer.c_str(), row.reader.c_str(), size == 1024 ? "1 KiB" : "1 MiB",
          static_cast<unsigned long long>(row.sent), static_cast<unsigned long long>(row.recorded),
          static_cast<unsigned long long>(row.lost), row.anchor_mbs, row.record_mbs,
          row.record_mbs / row.anchor_mbs, row.file_over_data);
      std::fputs(line, stdout);
      std::fflush(stdout);
      table << line;
    }
  }
  double load[3] = {0, 0, 0};
  if (FILE* f = std::fopen("/proc/loadavg", "r")) {
    if (std::fscanf(f, "%lf %lf %lf", &load[0], &load[1], &load[2]) != 3) load[0] = -1;
    std::fclose(f);
  }
  table << "\n"
        << mib << " MiB per row, zstd chunks, files in " << dir.string()
        << "; load average at the end " << load[0] << "\n";
  std::fputs(table.str().c_str(), stdout);
  if (!out.empty()) std::ofstream(out) << table.str();
  return 0;
}
