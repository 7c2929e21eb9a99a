#include "auv/recon/cluster/slurm_run.h"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <fstream>
#include <ostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "auv/recon/common/option_set.h"
#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/staged_output.h"
#include "auv/recon/pipeline/stages.h"

namespace fs = std::filesystem;

namespace auv::recon::cluster {

namespace {

constexpr const char* kFormat = "auv-recon-slurm 1";

fs::path jobsFile(const Survey& survey) { return survey.root() / "slurm" / "jobs.json"; }

/// A word for a POSIX shell, single-quoted.
std::string quoted(const std::string& word) {
  std::string out = "'";
  for (char c : word) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

/// Minutes for a job of `stage` (one of slurm.shards shards when `shard`): the option, else
/// three times its share of the stage's seconds in report.json.
int timeLimitMinutes(const Survey& survey, const std::string& stage, const SlurmOptions& slurm,
                     bool shard) {
  if (slurm.time_limit_min > 0) return slurm.time_limit_min;
  const nlohmann::json section = readReportSection(survey.report(), stage);
  const auto seconds = section.find("seconds");
  if (seconds == section.end() || !seconds->is_number()) return 0;
  const double share = seconds->get<double>() / (shard ? slurm.shards : 1);
  return std::max(10, static_cast<int>(std::ceil(3 * share / 60)));
}

std::string joined(const std::vector<std::string>& names) {
  std::string list;
  for (const std::string& name : names) list += (list.empty() ? "" : ", ") + name;
  return list;
}

/// The partition the jobs go to; refused when Slurm has no such partition.
std::string checkedPartition(const SlurmOptions& slurm) {
  std::string default_partition;
  const std::vector<std::string> names = slurm::partitions(&default_partition);
  if (slurm.partition.empty()) {
    if (default_partition.empty()) {
      throw ClusterError("--partition: the cluster has no default partition; one of: " +
                         joined(names));
    }
    return default_partition;
  }
  if (std::find(names.begin(), names.end(), slurm.partition) == names.end()) {
    throw ClusterError("--partition " + slurm.partition +
                       ": no such partition (the cluster has: " + joined(names) + ")");
  }
  return slurm.partition;
}

/// sbatch options common to every job of the run.
std::vector<std::string> commonArgs(const std::string& partition, const SlurmOptions& slurm) {
  std::vector<std::string> args = {"--partition=" + partition};
  if (slurm.cpus_per_task > 0)
    args.push_back("--cpus-per-task=" + std::to_string(slurm.cpus_per_task));
  if (slurm.mem_mb > 0) args.push_back("--mem=" + std::to_string(slurm.mem_mb));
  return args;
}

/// One short job that proves a compute node sees the survey folder (and may write it) and can
/// run `auv_recon`: a survey on a node's local disk would otherwise fail hours later.
void probeNodes(const Survey& survey, const std::string& partition, const SlurmOptions& slurm,
                const fs::path& auv_recon) {
  const fs::path dir = survey.root() / "slurm";
  const fs::path script = dir / "probe.sbatch";
  const fs::path mark = dir / "probe.seen";
  fs::remove(mark);
  // The mark, seen from here, proves the node writes where this machine reads.
  writeFileAtomically(script, "#!/bin/sh\ntest -x " + quoted(auv_recon.string()) + " && touch " +
                                  quoted(mark.string()) + "\n");
  std::vector<std::string> argv = {"sbatch",   "--parsable",
                                   "--wait",   "--job-name=auv-recon-probe",
                                   "--time=1", "--output=/dev/null"};
  for (const std::string& a : commonArgs(partition, slurm)) argv.push_back(a);
  argv.push_back(script.string());
  const CommandOutput result = runCommand(argv, slurm.probe_timeout_s);
  const bool seen = fs::exists(mark);
  fs::remove(mark);
  fs::remove(script);
  if (result.exit_code == 124) {
    // sbatch --parsable printed the probe's id before it waited: take the probe back.
    const std::string id = result.out.substr(0, result.out.find_first_of(";\n"));
    if (!id.empty()) runCommand({"scancel", id}, 60);
    throw ClusterError("the probe job did not finish within " +
                       std::to_string(static_cast<int>(slurm.probe_timeout_s)) + " s (partition " +
                       partition + " busy?): --probe-timeout-s longer, or 0 to submit without it");
  }
  if (result.exit_code != 0 || !seen) {
    throw ClusterError("the compute nodes of partition " + partition + " cannot see " +
                       survey.root().string() + " or run " + auv_recon.string() +
                       ": the survey folder and the install must be on a filesystem they share");
  }
}

nlohmann::json readJobs(const Survey& survey) {
  const fs::path file = jobsFile(survey);
  if (!fs::exists(file)) {
    throw std::invalid_argument(survey.root().string() +
                                ": no Slurm jobs were submitted for this survey (no " +
                                file.string() + ")");
  }
  std::ifstream in(file);
  nlohmann::json jobs;
  try {
    jobs = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw std::invalid_argument(file.string() + ": not JSON: " + e.what());
  }
  if (!jobs.is_object() || jobs.value("format", "") != kFormat || !jobs["jobs"].is_array()) {
    throw std::invalid_argument(file.string() + ": expected format '" + kFormat + "'");
  }
  return jobs;
}

std::string nowUtc() {
  const std::time_t now = std::time(nullptr);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  return text;
}

}  // namespace

void SlurmOptions::check() const {
  AUV_RECON_CHECK_OPTION(cpus_per_task >= 0, cpus_per_task, "must be >= 0 (0: Slurm's default)");
  AUV_RECON_CHECK_OPTION(mem_mb >= 0, mem_mb, "must be >= 0 MB (0: the partition's default)");
  AUV_RECON_CHECK_OPTION(time_limit_min >= 0, time_limit_min,
                         "must be >= 0 min (0: from report.json)");
  AUV_RECON_CHECK_OPTION(probe_timeout_s >= 0, probe_timeout_s, "must be >= 0 s (0: no probe)");
  AUV_RECON_CHECK_OPTION(shards >= 1 && shards <= 10000, shards, "must be in [1, 10000]");
}

void SlurmOptions::bind(OptionSet& set) {
  set.add("partition", &partition, "Slurm partition of the jobs (default: the cluster's)");
  set.add("cpus_per_task", &cpus_per_task, "CPUs per job (0: Slurm's default)");
  set.add("mem_mb", &mem_mb, "MB of memory per job (0: the partition's default)");
  set.add("time_limit_min", &time_limit_min,
          "minutes per job (0: 3x the stage's seconds in report.json, at least 10)");
  set.add("probe_timeout_s", &probe_timeout_s,
          "s a probe job may take to show the nodes see the survey (0: no probe)");
  set.add(
      "shards", &shards,
      "shardable stages (features, match, dense) run as an array of this many jobs, then a merge "
      "job");
}

std::vector<SubmittedJob> submitPipeline(const Survey& survey,
                                         const pipeline::PipelineOptions& options,
                                         const SlurmOptions& slurm, const fs::path& auv_recon,
                                         std::ostream& log) {
  slurm.check();
  pipeline::checkPipeline(options);
  slurm::checkAvailable();
  const std::string partition = checkedPartition(slurm);
  if (!fs::is_directory(survey.root())) {
    throw std::invalid_argument(survey.root().string() + ": no such survey folder");
  }
  if (fs::exists(jobsFile(survey))) {
    for (const SurveyJob& job : surveyJobs(survey)) {
      if (!slurm::finished(job.info.state)) {
        throw ClusterError("job " + job.job.id + " (" + job.job.stage + ") of an earlier " +
                           "submission is " + job.info.state + ": `auv recon status` to follow " +
                           "it, `auv recon cancel` to stop it");
      }
    }
  }
  const bool had_folder = fs::exists(survey.root() / "slurm");
  fs::create_directories(survey.root() / "slurm");
  if (slurm.probe_timeout_s > 0) {
    try {
      probeNodes(survey, partition, slurm, auv_recon);
    } catch (const ClusterError&) {
      if (!had_folder) fs::remove_all(survey.root() / "slurm");  // nothing but the probe's
      throw;
    }
  }

  const std::vector<std::string>& names = pipeline::stageNames();
  const auto first = std::find(names.begin(), names.end(), options.from);
  const auto last = std::find(names.begin(), names.end(), options.to);
  std::vector<SubmittedJob> jobs;
  nlohmann::json record = {
      {"format", kFormat}, {"submitted", nowUtc()}, {"jobs", nlohmann::json::array()}};
  // One job: `part` "" (the whole stage), "shards" (an array of slurm.shards tasks) or "merge".
  auto submitJob = [&](const std::string& stage, const std::string& part) {
    SubmittedJob job;
    job.stage = stage;
    job.part = part;
    const std::string base = stage + (part.empty() ? "" : "." + part);
    job.script = fs::path("slurm") / (base + ".sbatch");
    std::string command = quoted(auv_recon.string()) + " run " + quoted(survey.root().string()) +
                          " --from " + stage + " --to " + stage;
    if (!options.config.empty()) {
      command += " --config " + quoted(fs::absolute(options.config).string());
    }
    if (options.force) command += " --force";
    if (options.accept_partial) command += " --accept-partial";
    const std::string count = std::to_string(slurm.shards);
    if (part == "shards") command += " --shard \"$SLURM_ARRAY_TASK_ID\"/" + count;
    if (part == "merge") command += " --merge-shards " + count;
    writeFileAtomically(
        survey.root() / job.script,
        "#!/bin/sh\n# " + std::string(kFormat) + ": stage " + base +
            "\n# The stage's threads: the CPUs Slurm gave the job, not every core of the host.\n"
            "if [ -z \"${OMP_NUM_THREADS:-}\" ] && [ -n \"${SLURM_CPUS_ON_NODE:-}\" ]; then\n"
            "  OMP_NUM_THREADS=\"${SLURM_CPUS_PER_TASK:-$SLURM_CPUS_ON_NODE}\"\n"
            "  export OMP_NUM_THREADS\n"
            "fi\nexec " +
            command + "\n");
    std::vector<std::string> args = commonArgs(partition, slurm);
    args.push_back("--job-name=auv-recon-" + base);
    const std::string output_name = base + (part == "shards" ? "-%A_%a.log" : "-%j.log");
    args.push_back("--output=" + (survey.root() / "slurm" / output_name).string());
    if (part == "shards") args.push_back("--array=0-" + std::to_string(slurm.shards - 1));
    const int minutes = timeLimitMinutes(survey, stage, slurm, part == "shards");
    if (minutes > 0) args.push_back("--time=" + std::to_string(minutes));
    if (!jobs.empty()) {
      // afterok: a failed stage (or any shard of it) removes the later jobs, which never run on
      // its missing output.
      args.push_back("--dependency=afterok:" + jobs.back().id);
      args.push_back("--kill-on-invalid-dep=yes");
    }
    try {
      job.id = slurm::submit(args, survey.root() / job.script);
    } catch (const ClusterError& e) {
      // The jobs already queued would run a chain with a hole: take them back.
      std::vector<std::string> ids;
      for (const SubmittedJob& j : jobs) ids.push_back(j.id);
      slurm::cancel(ids);
      throw ClusterError(std::string(e.what()) + " (the " + std::to_string(ids.size()) +
                         " jobs submitted before it were cancelled)");
    }
    job.log =
        fs::path("slurm") / (base + "-" + job.id + (part == "shards" ? "_<task>.log" : ".log"));
    log << "run: " << base << ": submitted as job " << job.id
        << (part == "shards" ? " (" + count + " array tasks)" : "") << std::endl;
    record["jobs"].push_back({{"stage", job.stage},
                              {"part", job.part},
                              {"id", job.id},
                              {"script", job.script.string()},
                              {"log", job.log.string()}});
    jobs.push_back(job);
    writeFileAtomically(jobsFile(survey), record.dump(2) + "\n");
  };
  for (auto stage = first; stage <= last; ++stage) {
    if (slurm.shards > 1 && pipeline::findStage(*stage)->shardable()) {
      submitJob(*stage, "shards");
      submitJob(*stage, "merge");
    } else {
      submitJob(*stage, "");
    }
  }
  return jobs;
}

std::vector<SurveyJob> surveyJobs(const Survey& survey) {
  const nlohmann::json record = readJobs(survey);
  std::vector<SurveyJob> jobs;
  for (const nlohmann::json& entry : record["jobs"]) {
    if (!entry.is_object() || !entry["stage"].is_string() || !entry["id"].is_string()) {
      throw std::invalid_argument(jobsFile(survey).string() + ": a job without stage or id");
    }
    SurveyJob job;
    job.job.stage = entry["stage"];
    job.job.part = entry.value("part", "");
    job.job.id = entry["id"];
    job.job.script = entry.value("script", "");
    job.job.log = entry.value("log", "");
    job.info = slurm::job(job.job.id);
    jobs.push_back(job);
  }
  return jobs;
}

std::vector<std::string> cancelSurveyJobs(const Survey& survey) {
  std::vector<std::string> ids;
  for (const SurveyJob& job : surveyJobs(survey)) {
    if (!slurm::finished(job.info.state)) ids.push_back(job.job.id);
  }
  slurm::cancel(ids);
  return ids;
}

}  // namespace auv::recon::cluster
