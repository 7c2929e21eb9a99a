// `auv recon run <survey>`: every reconstruction stage in order over one survey folder
// (src/auv/recon/pipeline/README.md).
#include <filesystem>
#include <iostream>

#include "auv/recon/cluster/slurm_run.h"
#include "auv/recon/common/option_set.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/threads.h"
#include "auv/recon/pipeline/pipeline.h"
#include "auv/recon/tools/command.h"

namespace auv::recon {
namespace {

int runMain(const std::vector<std::string>& args) {
  limitLibraryThreads();
  return tools::runReportingErrors("run", [&] {
    pipeline::PipelineOptions options;
    cluster::SlurmOptions slurm;
    std::string survey, executor = "local";
    OptionSet set("run");
    set.positional("survey", &survey, "survey folder");
    options.bind(set);
    set.add("executor", &executor,
            "local (this process) or slurm (a chain of batch jobs; cluster/README.md)");
    slurm.bind(set);
    // --config is OptionSet's own (it applies the `run:` section); the stages read theirs.
    for (size_t i = 0; i < args.size(); ++i) {
      if (args[i] == "--config" && i + 1 < args.size()) options.config = args[i + 1];
      if (args[i].rfind("--config=", 0) == 0) options.config = args[i].substr(9);
    }
    if (!set.parse(args)) {
      std::string names;
      for (const std::string& name : pipeline::stageNames()) names += " " + name;
      std::cout << "Stages:" << names
                << ". A stage\n"
                   "whose output is newer than its input is skipped (--force runs it).\n"
                   "A partial result (sfm: fewer images registered than min_registered_ratio) "
                   "stops the run, exit 1, unless --accept-partial.\n"
                   "--config recon.yaml: one section per stage, the keys of its flags.\n";
      return tools::kExitOk;
    }
    options.check();
    if (executor == "slurm") {
      // The jobs run this very program, from the shared install.
      const auto jobs =
          cluster::submitPipeline(Survey(survey), options, slurm,
                                  std::filesystem::read_symlink("/proc/self/exe"), std::cerr);
      std::cout << "run: " << jobs.size() << " jobs submitted to Slurm (" << jobs.front().id << ".."
                << jobs.back().id << "); `auv recon status " << survey << "` follows them"
                << std::endl;
      return tools::kExitOk;
    }
    if (executor != "local") {
      throw OptionError("executor = " + executor + ": must be local or slurm");
    }
    const cluster::SlurmOptions defaults;
    if (slurm.partition != defaults.partition || slurm.cpus_per_task != defaults.cpus_per_task ||
        slurm.mem_mb != defaults.mem_mb || slurm.time_limit_min != defaults.time_limit_min ||
        slurm.probe_timeout_s != defaults.probe_timeout_s) {
      throw OptionError(
          "--partition, --cpus-per-task, --mem-mb, --time-limit-min and "
          "--probe-timeout-s are for --executor slurm");
    }
    const pipeline::PipelineResult s = pipeline::runPipeline(Survey(survey), options, std::cerr);
    size_t ran = 0;
    for (const auto& stage : s.stages) ran += stage.outcome == pipeline::StageOutcome::RAN;
    std::cout << "run: " << ran << " of " << s.stages.size() << " stages ran in " << s.seconds
              << " s -> " << Survey(survey).root().string() << std::endl;
    return tools::kExitOk;
  });
}

}  // namespace

AUV_RECON_COMMAND("run", 100,
                  "<survey>   every stage in order (--from, --to, --force, --executor slurm)",
                  runMain);

}  // namespace auv::recon
