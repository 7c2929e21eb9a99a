#pragma once
// glibc's allocator and multi-MiB buffers: chunks (1 MiB by default, up to 16 MiB) are
// allocated and freed several times each on both sides of a pull (read buffer, serialized
// sample, received sample, reply). With glibc's defaults such a buffer is mmap'ed, or the heap
// top above it is trimmed when it is freed, so the next one page-faults and is zeroed by the
// kernel page by page: 13-20 % of the CPU time of a pull here (reconstruction/bench/README.md).

#include <malloc.h>

#include <cstddef>

namespace auv::transfer {

/// Serves buffers below 32 MiB from the heap and returns freed heap memory to the system only
/// beyond 64 MiB. Process-wide, so called once by the processes that move file chunks: the
/// recorder component (configure) and `auv recon pull`. Idempotent.
inline void keepChunkBuffersInHeap() {
  constexpr int kMmapThreshold = 32 << 20;  // above the largest chunk (kLargestMaxChunkBytes)
  constexpr int kTrimThreshold = 64 << 20;  // a window of chunks in flight stays allocated
  mallopt(M_MMAP_THRESHOLD, kMmapThreshold);
  mallopt(M_TRIM_THRESHOLD, kTrimThreshold);
}

}  // namespace auv::transfer
