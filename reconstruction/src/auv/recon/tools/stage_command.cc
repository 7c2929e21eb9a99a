// `auv recon <stage> <survey>`: one command per stage of pipeline/stages.h, all alike: the
// stage's options as flags (and its `--config` section), its report on stdout, its warnings on
// stderr.
#include <iostream>
#include <memory>

#include "auv/recon/common/option_set.h"
#include "auv/recon/common/threads.h"
#include "auv/recon/pipeline/stages.h"
#include "auv/recon/tools/command.h"

namespace auv::recon {
namespace {

int stageMain(const Stage& stage, const std::vector<std::string>& args) {
  limitLibraryThreads();
  return tools::runReportingErrors(stage.name(), [&] {
    const std::unique_ptr<StageOptions> options = stage.defaultOptions();
    std::string survey;
    OptionSet set(stage.name());
    set.positional("survey", &survey, stage.surveyHelp());
    options->bind(set);
    if (!set.parse(args)) return tools::kExitOk;
    options->check();
    const StageReport report = stage.run(Survey(survey), *options);
    for (const std::string& warning : report.warnings) {
      std::cerr << "auv recon " << stage.name() << ": warning: " << warning << "\n";
    }
    for (const std::string& line : report.lines) std::cout << line << "\n";
    std::cout.flush();
    return tools::kExitOk;
  });
}

/// Registers every stage as a command, in the list's order from calibrate's place (10) in the
/// usage list: `pull` comes first (0) and `run` last (100).
const bool kRegistered = [] {
  int order = 10;
  for (const Stage* stage : pipeline::stages()) {
    tools::CommandRegistrar(
        stage->name(), order++, stage->usage(),
        [stage](const std::vector<std::string>& args) { return stageMain(*stage, args); });
  }
  return true;
}();

}  // namespace
}  // namespace auv::recon
