// `auv recon match <survey>`: candidate pairs, ratio + mutual matching, AC-RANSAC verification
// (src/auv/recon/features/README.md).
#include <iostream>

#include "auv/recon/common/option_set.h"
#include "auv/recon/features/match_stage.h"
#include "auv/recon/tools/command.h"

namespace auv::recon {
namespace {

int matchMain(const std::vector<std::string>& args) {
  return tools::runReportingErrors("match", [&] {
    features::MatchStageOptions options;
    std::string survey;
    OptionSet set("match");
    set.positional("survey", &survey, "survey folder (reads features/, writes features/matches/)");
    options.bind(set);
    if (!set.parse(args)) return tools::kExitOk;
    options.check();
    const features::MatchSummary summary = features::matchSurvey(Survey(survey), options);
    std::cout << "match: " << summary.verified_pairs << " of " << summary.candidate_pairs
              << " candidate pairs verified (" << summary.essential_pairs << " essential, "
              << summary.fundamental_pairs << " fundamental), " << summary.verified_matches
              << " inlier matches over " << summary.images << " images in " << summary.seconds
              << " s -> " << (Survey(survey).root() / "features" / "matches").string() << std::endl;
    return tools::kExitOk;
  });
}

}  // namespace

AUV_RECON_COMMAND("match", 45, "<survey>   match and verify image pairs (AC-RANSAC)", matchMain);

}  // namespace auv::recon
