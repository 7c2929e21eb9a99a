// Writer (and reader) throughput of auv_bag per compression, for 1 KiB and 1 MiB messages of
// two kinds of content, against an anchor measured in the same run: write() of the same
// message bytes to a file, fsync'ed like the writer's close(). Prints a table and writes it to
// --out (bench/README.md has figures and how to read them).
//
//   bag_bench [--mib N] [--dir DIR] [--out FILE]
//
// N MiB of messages per row (default 128); files go to DIR (default the system temp dir) and
// are removed.

#include <fcntl.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "auv/bag/mcap_reader.h"
#include "auv/bag/mcap_writer.h"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

double seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

/// `count` messages of `size` bytes: "random" (incompressible, like JPEG camera frames) or
/// "sensor" (float32 ranges of a smooth profile with noise, like sonar scans and clouds).
std::vector<std::vector<uint8_t>> makeMessages(size_t count, size_t size, const std::string& kind) {
  std::mt19937 generator(7);
  std::normal_distribution<float> noise(0.0f, 0.01f);
  std::vector<std::vector<uint8_t>> messages(count, std::vector<uint8_t>(size));
  for (size_t m = 0; m < count; ++m) {
    std::vector<uint8_t>& bytes = messages[m];
    if (kind == "random") {
      for (auto& b : bytes) b = static_cast<uint8_t>(generator());
      continue;
    }
    for (size_t i = 0; i + 4 <= size; i += 4) {
      const float range =
          5.0f + 2.0f * std::sin(0.01f * static_cast<float>(i / 4 + m)) + noise(generator);
      std::memcpy(&bytes[i], &range, 4);
    }
  }
  return messages;
}

/// write() of every message and fsync: what the bytes alone cost.
double anchorSeconds(const fs::path& path, const std::vector<std::vector<uint8_t>>& messages,
                     size_t repeats) {
  const auto start = Clock::now();
  std::FILE* file = std::fopen(path.c_str(), "wb");
  for (size_t r = 0; r < repeats; ++r) {
    for (const auto& m : messages) std::fwrite(m.data(), 1, m.size(), file);
  }
  std::fflush(file);
  ::fsync(::fileno(file));
  std::fclose(file);
  const double elapsed = seconds(start);
  fs::remove(path);
  return elapsed;
}

struct Row {
  double write_s = 0;
  double read_s = 0;
  uint64_t file_bytes = 0;
};

Row bagRow(const fs::path& path, const std::vector<std::vector<uint8_t>>& messages, size_t repeats,
           const std::string& compression) {
  Row row;
  auv::bag::McapWriterOptions options;
  options.compression = compression;
  options.overwrite = true;
  const auto start = Clock::now();
  {
    auv::bag::McapWriter writer(options);
    writer.open(path);
    const uint16_t schema =
        writer.addSchema("bench::Blob", "omgidl", "struct Blob { sequence<octet> data; };");
    const uint16_t channel = writer.addChannel(schema, "/bench", "cdr");
    uint64_t t = 1;
    for (size_t r = 0; r < repeats; ++r) {
      for (const auto& m : messages) {
        writer.write(channel, static_cast<uint32_t>(t), t, t, m);
        t += 1000;
      }
    }
    writer.close();
  }
  row.write_s = seconds(start);
  row.file_bytes = fs::file_size(path);
  const auto read_start = Clock::now();
  auv::bag::McapReader reader;
  reader.open(path);
  auto iterator = reader.messages();
  uint64_t read_bytes = 0;
  while (auto message = iterator.next()) read_bytes += message->message.data.size();
  row.read_s = seconds(read_start);
  if (read_bytes != messages.size() * messages[0].size() * repeats || !reader.damage().empty()) {
    std::cerr << "bag_bench: read back " << read_bytes << " bytes from " << path << "\n";
    std::exit(1);
  }
  fs::remove(path);
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  uint64_t mib = 128;
  fs::path dir = fs::temp_directory_path();
  fs::path out = "bag_bench_results.txt";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--mib") {
      mib = std::stoull(argv[i + 1]);
    } else if (flag == "--dir") {
      dir = argv[i + 1];
    } else if (flag == "--out") {
      out = argv[i + 1];
    } else {
      std::cerr << "bag_bench: unknown option " << flag << "\n";
      return 2;
    }
  }
  const fs::path path = dir / ("bag_bench_" + std::to_string(::getpid()) + ".mcap");
  std::ostringstream table;
  table << "| message | content | compression | write MB/s | anchor MB/s | write / anchor | "
           "file / data | read MB/s |\n|---|---|---|---|---|---|---|---|\n";
  std::cout << table.str() << std::flush;
  for (const size_t size : {size_t{1024}, size_t{1} << 20}) {
    for (const std::string kind : {"sensor", "random"}) {
      // 64 MiB of distinct messages at most, repeated to reach the total.
      const size_t distinct = std::max<size_t>(1, std::min<uint64_t>(mib, 64) * (1 << 20) / size);
      const size_t repeats = std::max<uint64_t>(1, mib * (1 << 20) / (distinct * size));
      const auto messages = makeMessages(distinct, size, kind);
      const double mb = static_cast<double>(distinct * size * repeats) / 1e6;
      for (const std::string compression : {"none", "zstd", "lz4"}) {
        const double anchor = anchorSeconds(path, messages, repeats);
        const Row row = bagRow(path, messages, repeats, compression);
        char line[256];
        std::snprintf(line, sizeof(line), "| %s | %s | %s | %.0f | %.0f | %.2f | %.3f | %.0f |\n",
                      size == 1024 ? "1 KiB" : "1 MiB", kind.c_str(), compression.c_str(),
                      mb / row.write_s, mb / anchor, anchor / row.write_s,
                      static_cast<double>(row.file_bytes) / (mb * 1e6), mb / row.read_s);
        table << line;
        std::cout << line << std::flush;
      }
    }
  }
  std::ofstream(out) << table.str();
  std::cout << "bag_bench: " << mib << " MiB per row; table written to " << out << "\n";
  return 0;
}
