#include "auv/recon/common/threads.h"

#include <sched.h>

#include <algorithm>
#include <cstdlib>
#include <string>
#include <thread>

#include <opencv2/core/utility.hpp>

namespace auv::recon {

int defaultThreadCount() {
  if (const char* text = std::getenv("OMP_NUM_THREADS")) {
    // OpenMP's form may list one count per nesting level ("4,2"): the first is ours.
    char* end = nullptr;
    const long count = std::strtol(text, &end, 10);
    if (end != text && count > 0 && (*end == '\0' || *end == ',')) {
      return static_cast<int>(std::min<long>(count, 4096));
    }
  }
  cpu_set_t mask;
  if (sched_getaffinity(0, sizeof(mask), &mask) == 0) {
    const int allowed = CPU_COUNT(&mask);
    if (allowed > 0) return allowed;
  }
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

void limitLibraryThreads() { cv::setNumThreads(defaultThreadCount()); }

}  // namespace auv::recon
