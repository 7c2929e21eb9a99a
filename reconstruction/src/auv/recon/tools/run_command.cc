// `auv recon run <survey>`: every reconstruction stage in order over one survey folder
// (src/auv/recon/pipeline/README.md).
#include <iostream>

#include "auv/recon/common/option_set.h"
#include "auv/recon/pipeline/pipeline.h"
#include "auv/recon/tools/command.h"

namespace auv::recon {
namespace {

int runMain(const std::vector<std::string>& args) {
  return tools::runReportingErrors("run", [&] {
    pipeline::PipelineOptions options;
    std::string survey;
    OptionSet set("run");
    set.positional("survey", &survey, "survey folder");
    options.bind(set);
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
    const pipeline::PipelineResult s = pipeline::runPipeline(Survey(survey), options, std::cerr);
    size_t ran = 0;
    for (const auto& stage : s.stages) ran += stage.outcome == pipeline::StageOutcome::RAN;
    std::cout << "run: " << ran << " of " << s.stages.size() << " stages ran in " << s.seconds
              << " s -> " << Survey(survey).root().string() << std::endl;
    return tools::kExitOk;
  });
}

}  // namespace

AUV_RECON_COMMAND("run", 100, "<survey>   every stage in order (--from, --to, --force)", runMain);

}  // namespace auv::recon
