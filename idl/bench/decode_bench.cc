// What the walk before each decode costs (GuardedPubSubType, idl/README.md "Decoding bytes from
// outside"): per message, the time of the guarded deserialize against the anchor measured in
// the same run, fastddsgen's deserialize alone, on samples as large as the system sends.
//
//   lib/auv_msgs/decode_bench [--repeats N] [--out FILE]
//
// N decodes per row (default 200); the table is printed and written to FILE (default
// decode_bench.tsv).
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <iostream>
#include <string>

#include "auv/msg/all.h"

namespace msg = auv::msg;

namespace {

using Clock = std::chrono::steady_clock;
using eprosima::fastrtps::rtps::SerializedPayload_t;

/// Mean seconds per call of `decode` over `repeats` calls.
double timePerCall(int repeats, const std::function<bool()>& decode) {
  const auto start = Clock::now();
  for (int i = 0; i < repeats; ++i) {
    if (!decode()) throw std::runtime_error("a valid payload was refused");
  }
  return std::chrono::duration<double>(Clock::now() - start).count() / repeats;
}

struct Row {
  std::string name;
  uint32_t bytes;
  double generated_s;
  double guarded_s;
};

/// Both decoders of T on the bytes of `sample`.
template <class T>
Row measure(const std::string& name, T sample, int repeats) {
  msg::GuardedPubSubType<T> guarded;
  typename msg::MessageTraits<T>::PubSubType generated;
  SerializedPayload_t payload(guarded.getSerializedSizeProvider(&sample)());
  if (!guarded.serialize(&sample, &payload)) throw std::runtime_error("serialize " + name);
  T out;
  Row row{name, payload.length, 0, 0};
  row.generated_s = timePerCall(repeats, [&] { return generated.deserialize(&payload, &out); });
  row.guarded_s = timePerCall(repeats, [&] { return guarded.deserialize(&payload, &out); });
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  int repeats = 200;
  std::string out_path = "decode_bench.tsv";
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--repeats" && i + 1 < argc) {
      repeats = std::stoi(argv[++i]);
    } else if (arg == "--out" && i + 1 < argc) {
      out_path = argv[++i];
    } else {
      std::cerr << "usage: decode_bench [--repeats N] [--out FILE]\n";
      return 2;
    }
  }
  std::vector<Row> rows;
  {
    msg::PlannerTree tree;  // the planner's tree after a long query
    tree.nodes().resize(20000);
    tree.parents().assign(20000, 1);
    tree.costs().assign(20000, 2.5);
    rows.push_back(measure("PlannerTree, 20 000 nodes", tree, repeats));
  }
  {
    msg::OctomapUpdate map;  // a FULL map of the canyon
    map.map_id("octomap");
    map.data().assign(1 << 20, 0x5a);
    rows.push_back(measure("OctomapUpdate, 1 MiB", map, repeats));
  }
  {
    msg::PointCloud cloud;  // one multibeam ping
    cloud.points().resize(256 * 16);
    rows.push_back(measure("PointCloud, 4 096 points", cloud, repeats));
  }
  {
    msg::StartMissionRequest request;  // the soak's mission
    request.mission_id("soak");
    request.queries().resize(36);
    rows.push_back(measure("StartMissionRequest, 36 queries", request, repeats));
  }
  std::ofstream out(out_path);
  out << "message\tbytes\tgenerated_us\tguarded_us\tratio\n";
  std::printf("%-34s %9s %14s %12s %7s\n", "message", "bytes", "fastddsgen us", "guarded us",
              "ratio");
  for (const Row& r : rows) {
    std::printf("%-34s %9u %14.1f %12.1f %7.2f\n", r.name.c_str(), r.bytes, r.generated_s * 1e6,
                r.guarded_s * 1e6, r.guarded_s / r.generated_s);
    out << r.name << '\t' << r.bytes << '\t' << r.generated_s * 1e6 << '\t' << r.guarded_s * 1e6
        << '\t' << r.guarded_s / r.generated_s << '\n';
  }
  std::cout << "results: " << out_path << "\n";
  return 0;
}
