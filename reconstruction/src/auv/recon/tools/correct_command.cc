// `auv recon correct <survey>`: colour correction and undistortion of the keyframes (paper
// sections 3.2 and 3.3; color/README.md).
#include <iostream>

#include "auv/recon/color/correct_stage.h"
#include "auv/recon/common/option_set.h"
#include "auv/recon/tools/command.h"

namespace auv::recon {
namespace {

int correctMain(const std::vector<std::string>& args) {
  return tools::runReportingErrors("correct", [&] {
    color::CorrectStageOptions options;
    std::string survey;
    OptionSet set("correct");
    set.positional("survey", &survey,
                   "survey folder (reads keyframes/ and calibration/, writes corrected/)");
    options.bind(set);
    if (!set.parse(args)) return tools::kExitOk;
    options.check();
    const color::CorrectStageResult result = color::correctSurvey(Survey(survey), options);
    for (const auto& camera : result.cameras) {
      std::cout << "correct: " << camera.camera << ": " << camera.images << " images"
                << (camera.undistorted ? ", undistorted" : ", not undistorted")
                << ", mean cast removed (alpha, beta) = (" << camera.mean_alpha << ", "
                << camera.mean_beta << ")\n";
    }
    std::cout << "correct: done in " << result.seconds << " s -> "
              << Survey(survey).corrected().string() << std::endl;
    return tools::kExitOk;
  });
}

}  // namespace

AUV_RECON_COMMAND("correct", 30, "<survey>   colour-correct and undistort the keyframes",
                  correctMain);

}  // namespace auv::recon
