#include "auv/recon/evaluate/figures_stage.h"

#include <iomanip>
#include <sstream>

#include "auv/recon/common/option_set.h"
#include "auv/recon/evaluate/evaluator.h"

namespace auv::recon::evaluate {

void FiguresStageOptions::bind(OptionSet& set) {
  set.add("ground_truth", &ground_truth,
          "simulated run folder for the alignment and the navigation (default: "
          "ground_truth_run of <survey>/simulation.json)");
  set.add("no_ground_truth", &no_ground_truth,
          "draw the per-camera figure in the reconstruction's own frame, no trajectory");
  set.add("image_size_px", &figures.image_size_px, "px: longer side of the images");
  set.add("point_size_px", &figures.point_size_px, "px: side of a drawn point");
  set.add("cloud", &figures.cloud, "auto, dense or sparse");
}

FiguresStageResult runFiguresStage(const Survey& survey, const FiguresStageOptions& options) {
  std::filesystem::path run = options.ground_truth;
  if (run.empty() && !options.no_ground_truth) run = recordedGroundTruth(survey);
  if (options.no_ground_truth) run.clear();
  return writeFigures(survey, run, options.figures);
}

StageReport FiguresStage::runWith(const Survey& survey, const FiguresStageOptions& options) const {
  const FiguresStageResult result = runFiguresStage(survey, options);
  StageReport report;
  std::ostringstream line;
  line << "figures: " << result.points << " points of the " << result.cloud
       << " cloud by camera combination:";
  for (const auto& [name, count] : result.points_per_combination) {
    line << " " << name << " " << std::fixed << std::setprecision(1)
         << 100.0 * count / result.points << " %;";
  }
  report.lines.push_back(line.str());
  if (!result.trajectory) {
    report.lines.push_back("figures: no trajectory figure (needs --ground-truth <run>)");
  }
  for (const auto& file : result.files) report.lines.push_back("figures: -> " + file.string());
  report.summary =
      std::to_string(result.files.size()) + " figures in " + (survey.root() / "figures").string();
  return report;
}

}  // namespace auv::recon::evaluate
