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
    mesh::SurfaceOptions& s = options.surface;
    std::string survey;
    OptionSet set("mesh");
    set.positional("survey", &survey, "survey folder (reads dense/fused.ply, writes mesh/)");
    set.add("poisson_depth", &s.poisson_depth, "Poisson octree depth (finest cell = extent/2^d)");
    set.add("poisson_scale", &s.poisson_scale, "Poisson cube = cloud extent x this");
    set.add("poisson_linear_fit", &s.poisson_linear_fit, "Poisson linear iso-value fit");
    set.add("max_edge_factor", &s.max_edge_factor,
            "remove triangles with an edge > this x local spacing (0: off)");
    set.add("spacing_neighbors", &s.spacing_neighbors, "neighbours of the local point spacing");
    set.add("density_quantile", &s.density_quantile,
            "remove vertices below this quantile of Poisson density (0: off)");
    set.add("density_drop_levels", &s.density_drop_levels,
            "remove vertices this many octree levels below the median density (0: off)");
    set.add("min_component_fraction", &s.min_component_fraction,
            "remove components smaller than this fraction of the largest");
    set.add("min_points", &s.min_points, "fewer cloud points: the stage fails");
    set.add("threads", &s.threads, "Poisson threads (-1: all)");
    set.add("write_untrimmed", &options.write_untrimmed, "also write mesh/mesh_untrimmed.ply");
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
