#include "auv/recon/mesh/mesh_stage.h"

#include <chrono>
#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "auv/recon/common/progress.h"
#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/staged_output.h"
#include "auv/recon/scene/mesh_io.h"

namespace fs = std::filesystem;
namespace o3d = open3d::geometry;

namespace auv::recon::mesh {

void MeshStageOptions::bind(OptionSet& set) {
  SurfaceOptions& s = surface;
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
  set.add("write_untrimmed", &write_untrimmed, "also write mesh/mesh_untrimmed.ply");
}

MeshStageResult runMeshStage(const Survey& survey, const MeshStageOptions& options) {
  options.check();
  const auto start = std::chrono::steady_clock::now();
  const fs::path input = survey.dense() / "fused.ply";
  const o3d::PointCloud cloud = scene::readCloud(input, "mesh", "dense");
  MeshStageResult summary;
  summary.cloud_points = cloud.points_.size();
  std::cerr << "mesh: " << cloud.points_.size() << " points from " << input.string()
            << ", Poisson depth " << options.surface.poisson_depth << std::endl;

  Progress progress("mesh", "steps", 3);
  SurfaceResult result;
  try {
    result = reconstructSurface(cloud, options.surface);
  } catch (const StageError& e) {
    const std::string cause = std::string(e.what()).substr(e.stage().size() + 2);
    throw StageError("mesh", input.string() + ": " + cause);
  }
  progress.advance(2);
  summary.stats = result.stats;
  summary.area_untrimmed = surfaceArea(*result.untrimmed);
  summary.area = surfaceArea(*result.trimmed);

  StagedOutput staged(survey.mesh());
  scene::writeMeshPly(staged.path() / "mesh.ply", *result.trimmed);
  if (options.write_untrimmed)
    scene::writeMeshPly(staged.path() / "mesh_untrimmed.ply", *result.untrimmed);
  staged.commit();
  progress.advance();
  progress.finish();
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  const SurfaceOptions& o = options.surface;
  const TrimStats& s = summary.stats;
  nlohmann::json section = {{"input", "dense/fused.ply"},
                            {"cloud_points", summary.cloud_points},
                            {"poisson_vertices", s.poisson_vertices},
                            {"poisson_triangles", s.poisson_triangles},
                            {"removed_long_edge_triangles", s.removed_long_edges},
                            {"removed_low_density_triangles", s.removed_low_density},
                            {"removed_small_component_triangles", s.removed_components},
                            {"vertices", s.vertices},
                            {"triangles", s.triangles},
                            {"area_untrimmed_m2", summary.area_untrimmed},
                            {"area_m2", summary.area},
                            {"finest_cell_m", s.finest_cell},
                            {"median_point_spacing_m", s.median_spacing},
                            {"density_threshold", s.density_threshold},
                            {"seconds", summary.seconds},
                            {"options",
                             {{"poisson_depth", o.poisson_depth},
                              {"poisson_scale", o.poisson_scale},
                              {"poisson_linear_fit", o.poisson_linear_fit},
                              {"max_edge_factor", o.max_edge_factor},
                              {"spacing_neighbors", o.spacing_neighbors},
                              {"density_quantile", o.density_quantile},
                              {"density_drop_levels", o.density_drop_levels},
                              {"min_component_fraction", o.min_component_fraction},
                              {"min_points", o.min_points}}}};
  updateReport(survey.report(), "mesh", section);
  return summary;
}

StageReport MeshStage::runWith(const Survey& survey, const MeshStageOptions& options) const {
  const MeshStageResult result = runMeshStage(survey, options);
  std::ostringstream line;
  line << "mesh: " << result.stats.triangles << " triangles (" << result.stats.poisson_triangles
       << " from Poisson; removed " << result.stats.removed_long_edges << " long-edge, "
       << result.stats.removed_low_density << " low-density, " << result.stats.removed_components
       << " in small components), area " << result.area << " m2 of " << result.area_untrimmed
       << " m2, " << result.seconds << " s -> " << (survey.mesh() / "mesh.ply").string();
  StageReport report;
  report.lines.push_back(line.str());
  report.summary = "mesh in " + survey.mesh().string();
  return report;
}

}  // namespace auv::recon::mesh
