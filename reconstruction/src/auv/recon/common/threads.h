#pragma once
// How many threads a stage uses when its options leave it to the machine.

namespace auv::recon {

/// OMP_NUM_THREADS when set to a positive number (a Slurm job's script sets it to the CPUs the
/// job was given), else the CPUs this process may run on (its affinity mask: a cgroup's or
/// taskset's cpuset), else the machine's hardware threads; at least 1. OpenMP's parallel
/// regions follow the same variable and mask, so a stage's own threads and its OpenMP loops agree.
int defaultThreadCount();

/// Sizes OpenCV's own thread pool (TBB in Debian's build, which follows the affinity mask but
/// not OMP_NUM_THREADS) to defaultThreadCount(): a Slurm job given 1 CPU otherwise ran SIFT and
/// every other OpenCV loop on all the host's cores. Called once by each `auv recon` command.
void limitLibraryThreads();

}  // namespace auv::recon
