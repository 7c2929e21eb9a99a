// `auv recon dense <survey>`: depth maps and the fused point cloud (dense/README.md).
#include <iostream>

#include "auv/recon/common/option_set.h"
#include "auv/recon/dense/dense_stage.h"
#include "auv/recon/tools/command.h"

namespace auv::recon {
namespace {

int denseMain(const std::vector<std::string>& args) {
  return tools::runReportingErrors("dense", [&] {
    dense::DenseOptions options;
    std::string survey_path;
    OptionSet set("dense");
    set.positional("survey", &survey_path, "survey folder (reads sparse/ and corrected/)");
    options.bind(set);
    if (!set.parse(args)) return tools::kExitOk;
    options.check();
    const dense::DenseSummary summary = dense::runDense(Survey(survey_path), options);
    std::cout << "dense: " << summary.depth_maps << " depth maps (" << summary.width << "x"
              << summary.height << " px), " << summary.points << " points ("
              << summary.depths_inconsistent << " depths dropped as inconsistent) in "
              << summary.seconds << " s; " << (Survey(survey_path).dense() / "fused.ply").string()
              << std::endl;
    return tools::kExitOk;
  });
}

}  // namespace

AUV_RECON_COMMAND("dense", 60, "<survey>   depth maps and the fused point cloud (dense/)",
                  denseMain);

}  // namespace auv::recon
