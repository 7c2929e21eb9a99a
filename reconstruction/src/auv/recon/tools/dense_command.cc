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
    set.add("max_image_size", &options.max_image_size,
            "px: longer side depth maps are computed at (0: full size)");
    set.add("min_registered_images", &options.min_registered_images,
            "fewer registered images in sparse/: error");
    set.add("min_points", &options.min_points, "a fused cloud with fewer points: error");
    set.add("image_cache", &options.image_cache, "images kept in memory between masters");
    set.add("keep_depth_maps", &options.keep_depth_maps, "keep dense/depth_maps/");
    dense::NeighbourOptions& n = options.neighbours;
    set.add("max_neighbours", &n.max_neighbours, "images matched against each master");
    set.add("min_shared_points", &n.min_shared_points, "sparse points a neighbour must share");
    set.add("min_angle_deg", &n.min_angle_deg, "deg: smallest median triangulation angle");
    set.add("max_angle_deg", &n.max_angle_deg, "deg: largest median triangulation angle");
    set.add("good_angle_deg", &n.good_angle_deg, "deg: smaller angles are down-weighted");
    set.add("depth_percentile", &n.depth_percentile,
            "fraction of the master's sparse depths cut at each end");
    set.add("depth_margin", &n.depth_margin, "the depth range widened by this fraction");
    set.add("min_depth_points", &n.min_depth_points, "sparse points a master must see");
    dense::MatcherOptions& m = options.matcher;
    set.add("pyramid_levels", &m.pyramid_levels, "levels of the coarse-to-fine pyramid");
    set.add("min_level_size", &m.min_level_size, "px: smallest pyramid level (longer side)");
    set.add("window_radius", &m.window_radius, "px: NCC window is (2r+1)^2");
    set.add("best_k", &m.best_k, "the cost averages the k best neighbours' NCC");
    set.add("label_px", &m.label_px, "px of epipolar displacement per depth label");
    set.add("max_labels", &m.max_labels, "labels of the coarsest level's full search");
    set.add("search_labels", &m.search_labels, "labels per pixel at finer levels");
    set.add("range_margin", &m.range_margin, "labels added around the coarser level's range");
    set.add("p1", &m.p1, "SGM penalty for a one-label change (512 = 1 unit of 1 - NCC)");
    set.add("p2", &m.p2, "SGM penalty for larger jumps");
    set.add("p2_edge_grey", &m.p2_edge_grey, "grey levels: P2 / (1 + |dI| / this)");
    set.add("directions", &m.directions, "SGM paths: 4 or 8");
    set.add("min_ncc", &m.min_ncc, "a depth needs this aggregated NCC");
    set.add("uniqueness", &m.uniqueness, "margin of the best over the second-best cost");
    set.add("min_texture_grey", &m.min_texture_grey, "grey levels: window std below: no match");
    set.add("speckle_size", &m.speckle_size, "px: smaller isolated depth blobs are removed");
    set.add("speckle_labels", &m.speckle_labels, "labels: step separating speckle blobs");
    set.add("strip_rows", &m.strip_rows, "rows per cost strip (strips run in parallel)");
    dense::FusionOptions& f = options.fusion;
    set.add("min_consistent", &f.min_consistent, "neighbours whose depth maps must agree");
    set.add("depth_tolerance", &f.depth_tolerance, "relative depth difference to agree");
    set.add("reprojection_px", &f.reprojection_px, "px: forward-backward reprojection error");
    set.add("normal_step", &f.normal_step, "px between the depths normals come from");
    set.add("pixel_step", &f.pixel_step, "px: new points start on this grid of a master");
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
