// `auv recon sfm <survey>`: incremental structure from motion over the verified matches
// (src/auv/recon/sfm/README.md).
#include <iostream>

#include "auv/recon/common/option_set.h"
#include "auv/recon/sfm/sfm_stage.h"
#include "auv/recon/tools/command.h"

namespace auv::recon {
namespace {

int sfmMain(const std::vector<std::string>& args) {
  return tools::runReportingErrors("sfm", [&] {
    sfm::SfmStageOptions options;
    std::string survey;
    OptionSet set("sfm");
    set.positional("survey", &survey,
                   "survey folder (reads corrected/, features/; writes sparse/)");
    options.bind(set);
    if (!set.parse(args)) return tools::kExitOk;
    options.check();
    const sfm::SfmSummary s = sfm::reconstructSurvey(Survey(survey), options);
    std::cout << "sfm: " << s.images_registered << " of " << s.images_total
              << " images registered, " << s.points << " points, mean track length "
              << s.mean_track_length << ", mean reprojection error " << s.mean_reprojection_error_px
              << " px";
    if (s.navigation.applied) {
      std::cout << ", aligned to the navigation (" << s.navigation.images << " images, rms "
                << s.navigation.rms_m << " m)";
    }
    std::cout << " in " << s.seconds << " s -> " << Survey(survey).sparse().string() << std::endl;
    return tools::kExitOk;
  });
}

}  // namespace

AUV_RECON_COMMAND("sfm", 50, "<survey>   incremental structure from motion (sparse model)",
                  sfmMain);

}  // namespace auv::recon
