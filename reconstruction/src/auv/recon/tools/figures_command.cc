// `auv recon figures <survey>`: per-camera contribution and trajectory comparison (paper
// Figures 19 and 20; src/auv/recon/evaluate/README.md).
#include <iomanip>
#include <iostream>

#include "auv/recon/common/option_set.h"
#include "auv/recon/evaluate/evaluator.h"
#include "auv/recon/evaluate/figures.h"
#include "auv/recon/tools/command.h"

namespace auv::recon {
namespace {

int figuresMain(const std::vector<std::string>& args) {
  return tools::runReportingErrors("figures", [&] {
    evaluate::FiguresOptions o;
    std::string survey_path, ground_truth;
    bool no_ground_truth = false;
    OptionSet set("figures");
    set.positional("survey", &survey_path,
                   "survey folder (reads sparse/, dense/fused.ply + fused_views.bin; writes "
                   "figures/)");
    set.add("ground_truth", &ground_truth,
            "simulated run folder for the alignment and the navigation (default: "
            "ground_truth_run of <survey>/simulation.json)");
    set.add("no_ground_truth", &no_ground_truth,
            "draw the per-camera figure in the reconstruction's own frame, no trajectory");
    set.add("image_size_px", &o.image_size_px, "px: longer side of the images");
    set.add("point_size_px", &o.point_size_px, "px: side of a drawn point");
    set.add("cloud", &o.cloud, "auto, dense or sparse");
    if (!set.parse(args)) return tools::kExitOk;
    o.check();
    const Survey survey(survey_path);
    std::filesystem::path run = ground_truth;
    if (run.empty() && !no_ground_truth) run = evaluate::recordedGroundTruth(survey);
    if (no_ground_truth) run.clear();
    const evaluate::FiguresResult result = evaluate::writeFigures(survey, run, o);
    std::cout << "figures: " << result.points << " points of the " << result.cloud
              << " cloud by camera combination:";
    for (const auto& [name, count] : result.points_per_combination) {
      std::cout << " " << name << " " << std::fixed << std::setprecision(1)
                << 100.0 * count / result.points << " %;";
    }
    std::cout << "\n";
    if (!result.trajectory) {
      std::cout << "figures: no trajectory figure (needs --ground-truth <run>)\n";
    }
    for (const auto& file : result.files) std::cout << "figures: -> " << file.string() << "\n";
    return tools::kExitOk;
  });
}

}  // namespace

AUV_RECON_COMMAND("figures", 95,
                  "<survey>   per-camera contribution and trajectory figures (Figs. 19, 20)",
                  figuresMain);

}  // namespace auv::recon
