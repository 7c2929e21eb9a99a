#pragma once
// Slurm, through the commands every cluster has (sbatch, squeue, scontrol, scancel, sinfo):
// they work against any Slurm the user's environment points at (SLURM_CONF), with no client
// library to match to the cluster's version.

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace auv::recon::cluster {

/// What a finished command gave.
struct CommandOutput {
  int exit_code = -1;  ///< 127: not found; 124: stopped after its time limit
  std::string out, err;
};

/// Runs `argv` (argv[0] looked up on PATH) without a shell, stdin from /dev/null, and waits
/// for it; after `timeout_s` (0: none) it is killed and exit_code is 124. Throws
/// std::runtime_error when it cannot be started at all (pipes).
CommandOutput runCommand(const std::vector<std::string>& argv, double timeout_s = 0);

/// Slurm cannot be used as asked (not installed, a partition it does not have, a refused
/// submission). A config::RuntimeFailure would be exit 1; this is a usage problem of the
/// cluster, named with what to do: exit 2 like a bad option.
class ClusterError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// One job as Slurm reports it.
struct JobInfo {
  std::string id;
  /// PENDING, RUNNING, COMPLETED, FAILED, CANCELLED, TIMEOUT, OUT_OF_MEMORY, NODE_FAIL, ...;
  /// UNKNOWN when Slurm no longer knows the job (it left the controller's memory, MinJobAge).
  std::string state = "UNKNOWN";
  std::string reason;     ///< why it waits (Dependency, Resources, DependencyNeverSatisfied)
  std::string nodes;      ///< where it runs or ran
  std::string elapsed;    ///< run time, [D-]HH:MM:SS
  std::string exit_code;  ///< "code:signal"
};

namespace slurm {

/// Throws ClusterError when sbatch is not on PATH.
void checkAvailable();
/// The partitions (the default one marked by Slurm's '*' is returned without it); `default_`
/// gets the default partition's name (empty: none). Throws ClusterError when no controller
/// answers.
std::vector<std::string> partitions(std::string* default_partition = nullptr);
/// sbatch `args` `script`; returns the job id. Throws ClusterError with sbatch's message.
std::string submit(const std::vector<std::string>& args, const std::filesystem::path& script);
/// scontrol show job: the job's state (UNKNOWN for a job Slurm does not know).
JobInfo job(const std::string& id);
/// scancel of `ids`; throws ClusterError with scancel's message.
void cancel(const std::vector<std::string>& ids);

/// True for states after which a job does nothing more.
bool finished(const std::string& state);

}  // namespace slurm
}  // namespace auv::recon::cluster
