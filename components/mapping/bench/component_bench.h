#pragma once
// The mapping component on real DDS, fed with the benchmark stream: in this process (its own
// node and participant, spun by this thread; the feeder publishes from another thread) or in
// a child process hosting it as `auv run mapping` does (this process feeds it and reads
// map/update like the planner).
//
// End of stream: the component's own counters (beams or clouds inserted + dropped = all sent),
// read by the thread that spins it after each batch of callbacks and shared with the feeder (in
// the child through a memfd page), so the time is exact and the feeder can keep a window. The
// final map is compared byte for byte with the library's (.ot, log-odds): equal means every
// measurement went in, placed as by the library. In the child case that map travels as the
// FULL map/update the reader asks for with map/request_full.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "auv/interfaces/backend.h"
#include "bench_stream.h"

namespace auv::mapping::bench {

struct ComponentRun {
  interfaces::Vendor vendor = interfaces::Vendor::CYCLONEDDS;  ///< of the component
  std::optional<interfaces::Vendor> feeder_vendor;  ///< of the feeder and map reader; = vendor
  int domain = 86;
  bool child_process = false;
  std::string self_executable;  ///< to start the child (this program with --serve)
  /// QoS profile of nav/odometry, sonar/beam and sonar/scan on both sides ("" = the topics'
  /// defaults). The default profiles drop what a slower reader has not taken yet, which is
  /// what a live sensor wants; a replayed stream must not lose anything: bulk_transfer
  /// (reliable, keep all) makes the publisher wait for the component instead.
  std::string qos = "bulk_transfer";
  std::vector<std::string> parameters;  ///< extra component parameters, "name:=value"
  /// Measurements the feeder may send ahead of what the component took: below the keep-all
  /// readers' 256 samples, which then never reject anything (see Feeder).
  std::size_t beam_window = 200;
  std::size_t cloud_window = 64;
  /// The component's executor thread alone on kWorkCpu (where the raw baseline runs too),
  /// everything else (feeder, DDS threads of both sides) on kOtherCpu.
  bool pin = false;
  double timeout_s = 300.0;
};

constexpr int kWorkCpu = 1;
constexpr int kOtherCpu = 0;
/// Restricts the calling thread (and threads it creates later) to `cpu`; false if refused.
bool pinThisThread(int cpu);

struct ComponentResult {
  bool ok = false;
  std::string error;  ///< why not ok
  std::size_t sent = 0;
  uint64_t dropped = 0;  ///< by the component (in this process)
  double seconds = 0.0;  ///< first publish -> all taken by the component
  double per_s = 0.0;    ///< measurements (beams or points) per second over `seconds`
  /// CPU seconds over `seconds`: the component's executor thread, and every thread of the
  /// pipeline (component, feeder and map reader, DDS threads of both sides).
  double executor_cpu_s = 0.0;
  double total_cpu_s = 0.0;
  int publish_retries = 0;  ///< writes that timed out (reader full for > max_blocking_time)
  std::string map_ot;       ///< final map, AbstractOcTree::write
  int updates = 0;          ///< map/update samples received (child)
};

/// Sends every beam with its odometry and measures.
ComponentResult runBeams(const Stream& stream, const ComponentRun& run);
/// Sends every cloud and measures points per second.
ComponentResult runClouds(const Stream& stream, std::size_t points_per_cloud,
                          const ComponentRun& run);

/// Child process: hosts the component like `auv run mapping` (interfaces::runComponents)
/// until SIGTERM, writing its progress to the shared page `progress_fd`. `parameters` are
/// "name:=value".
int serveComponent(interfaces::Vendor vendor, int domain,
                   const std::vector<std::string>& parameters, int progress_fd, bool pin);

}  // namespace auv::mapping::bench
