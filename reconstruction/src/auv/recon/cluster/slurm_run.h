#pragma once
// `auv recon run --executor slurm`, `auv recon status`, `auv recon cancel` (cluster/README.md):
// the stages of a run submitted as a chain of Slurm batch jobs over a survey folder on a
// filesystem the compute nodes share. Each job is `auv-recon run <survey> --from S --to S`, so
// a job skips a stage whose output is up to date exactly as a local run does, and a chain
// submitted again after a failure redoes only what is missing.
//
// What was submitted is kept in <survey>/slurm/jobs.json (replaced whole):
//
//   {"format": "auv-recon-slurm 1", "submitted": "2026-11-29T21:00:00Z",
//    "jobs": [{"stage": "features", "part": "shards", "id": "12",
//              "script": "slurm/features.shards.sbatch", "log":
//              "slurm/features.shards-12_<task>.log"},
//             {"stage": "features", "part": "merge", "id": "13", ...},
//             {"stage": "match", "part": "", "id": "14", ...}, ...]}

#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

#include "auv/recon/cluster/slurm.h"
#include "auv/recon/common/survey.h"
#include "auv/recon/pipeline/pipeline.h"

namespace auv::recon {
class OptionSet;
}

namespace auv::recon::cluster {

struct SlurmOptions {
  std::string partition;  ///< empty: the cluster's default partition
  int cpus_per_task = 0;  ///< 0: Slurm's default
  int mem_mb = 0;         ///< per job; 0: the partition's default
  /// Minutes per job; 0: three times the stage's seconds in the survey's report.json (at least
  /// 10 min), the partition's limit for a stage that never ran.
  int time_limit_min = 0;
  /// Shardable stages (Stage::shardable: features, match, dense) run as a job array of this many
  /// tasks, each one shard, then a merge job; 1: one job per stage.
  int shards = 1;
  /// Before submitting, one short job checks that the compute nodes see the survey folder
  /// (writable) and can run this auv-recon; seconds it may wait for a node.
  double probe_timeout_s = 300;

  /// Throws OptionError naming the field.
  void check() const;
  void bind(OptionSet& set);
};

struct SubmittedJob {
  std::string stage;
  std::string part;  ///< "" (the whole stage), "shards" (a job array) or "merge"
  std::string id;
  std::filesystem::path script, log;  ///< relative to the survey folder
};

/// Submits the stages options.from..options.to as jobs chained by `afterok`, after checking
/// everything that can be checked here: the pipeline options and config file (as a local run
/// does), Slurm itself, the partition, and (the probe) that the compute nodes see the survey
/// and `auv_recon`; a refusal submits nothing. Refused too while jobs of an earlier submission
/// for this survey are still queued or running. `auv_recon` is the program the jobs run (this
/// one); the jobs inherit this environment (sbatch's default), so the install need only be on
/// the shared filesystem. `log` gets one line per job.
std::vector<SubmittedJob> submitPipeline(const Survey& survey,
                                         const pipeline::PipelineOptions& options,
                                         const SlurmOptions& slurm,
                                         const std::filesystem::path& auv_recon, std::ostream& log);

struct SurveyJob {
  SubmittedJob job;
  JobInfo info;
};

/// The jobs of the survey's last submission with Slurm's view of each. Throws
/// std::invalid_argument when the survey has no slurm/jobs.json (nothing was submitted) or it
/// is damaged (named).
std::vector<SurveyJob> surveyJobs(const Survey& survey);

/// Cancels the survey's jobs that are not finished; returns their ids.
std::vector<std::string> cancelSurveyJobs(const Survey& survey);

}  // namespace auv::recon::cluster
