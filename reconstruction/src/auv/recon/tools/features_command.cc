// `auv recon features <survey>`: SIFT keypoints and descriptors of every corrected image
// (src/auv/recon/features/README.md).
#include <iostream>

#include "auv/recon/common/option_set.h"
#include "auv/recon/features/sift_extractor.h"
#include "auv/recon/tools/command.h"

namespace auv::recon {
namespace {

int featuresMain(const std::vector<std::string>& args) {
  return tools::runReportingErrors("features", [&] {
    features::ExtractionOptions options;
    std::string survey;
    OptionSet set("features");
    set.positional("survey", &survey, "survey folder (reads corrected/, writes features/)");
    options.bind(set);
    if (!set.parse(args)) return tools::kExitOk;
    options.check();
    const features::ExtractionSummary summary =
        features::extractSurveyFeatures(Survey(survey), options);
    std::cout << "features: " << summary.images << " images, " << summary.features << " keypoints ("
              << summary.min_features << "-" << summary.max_features << " per image) in "
              << summary.seconds << " s -> " << (Survey(survey).root() / "features").string()
              << std::endl;
    return tools::kExitOk;
  });
}

}  // namespace

AUV_RECON_COMMAND("features", 40, "<survey>   SIFT features of the corrected images", featuresMain);

}  // namespace auv::recon
