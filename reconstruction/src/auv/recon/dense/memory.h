#pragma once
// Peak resident memory of this process, per sub-stage: Linux's VmHWM, which writing "5" to
// /proc/self/clear_refs resets to the current resident size.

#include <cstddef>

namespace auv::recon::dense {

/// Peak resident set size since start or the last resetPeakMemory(), bytes (0 if unknown).
size_t peakMemoryBytes();
/// Current resident set size, bytes (0 if unknown).
size_t currentMemoryBytes();
/// Starts a new peak measurement; false when the kernel does not allow it (the peak then
/// stays the process's peak so far).
bool resetPeakMemory();

}  // namespace auv::recon::dense
