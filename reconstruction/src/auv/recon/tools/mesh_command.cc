// `auv recon mesh <survey>`: screened Poisson surface of the dense cloud, trimmed
// (src/auv/recon/mesh/README.md).
#include <iostream>

#include "auv/recon/common/option_set.h"
#include "auv/recon/mesh/mesh_stage.h"
#include "auv/recon/tools/command.h"

namespace auv::recon {
namespace {

int meshMain(const std::vector<std::string>& args) {
  return tools::runReportingErrors("mesh", [&] {
    mesh::MeshStageOptions options;
    std::string survey;
    OptionSet set("mesh");
    set.positional("survey", &survey, "survey folder (reads dense/fused.ply, writes mesh/)");
    options.bind(set);
    if (!set.parse(args)) return tools::kExitOk;
    options.check();
    const auto summary = mesh::runMeshStage(Survey(survey), options);
    std::cout << "mesh: " << summary.stats.triangles << " triangles ("
              << summary.stats.poisson_triangles << " from Poisson; removed "
              << summary.stats.removed_long_edges << " long-edge, "
              << summary.stats.removed_low_density << " low-density, "
              << summary.stats.removed_components << " in small components), area " << summary.area
              << " m2 of " << summary.area_untrimmed << " m2, " << summary.seconds << " s -> "
              << (Survey(survey).mesh() / "mesh.ply").string() << std::endl;
    return tools::kExitOk;
  });
}

}  // namespace

AUV_RECON_COMMAND("mesh", 70, "<survey>   Poisson surface of the dense cloud, trimmed", meshMain);

}  // namespace auv::recon
