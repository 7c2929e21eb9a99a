// `auv recon keyframes <survey>`: keyframe selection (paper section 3.1; keyframes/README.md).
#include <iostream>

#include "auv/recon/common/option_set.h"
#include "auv/recon/keyframes/stage.h"
#include "auv/recon/tools/command.h"

namespace auv::recon {
namespace {

int keyframesMain(const std::vector<std::string>& args) {
  return tools::runReportingErrors("keyframes", [&] {
    keyframes::KeyframeStageOptions options;
    std::string survey;
    OptionSet set("keyframes");
    set.positional("survey", &survey, "survey folder (reads recordings/, writes keyframes/)");
    options.bind(set);
    if (!set.parse(args)) return tools::kExitOk;
    options.check();
    const keyframes::KeyframeStageResult result =
        keyframes::selectSurveyKeyframes(Survey(survey), options);
    for (const auto& camera : result.cameras) {
      std::cout << "keyframes: " << camera.camera << ": " << camera.keyframes << " keyframes of "
                << camera.frames << " frames (" << camera.videos.size() << " videos), "
                << camera.rejected << " frames refused (rejected.csv)\n";
    }
    for (const auto& problem : result.problems) {
      std::cerr << "auv recon keyframes: warning: " << problem << "\n";
    }
    std::cout << "keyframes: done in " << result.seconds << " s -> "
              << Survey(survey).keyframes().string() << std::endl;
    return tools::kExitOk;
  });
}

}  // namespace

AUV_RECON_COMMAND("keyframes", 20, "<survey>   select sharp keyframes from the recordings",
                  keyframesMain);

}  // namespace auv::recon
