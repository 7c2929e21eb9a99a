#include "auv/recon/evaluate/survey_truth.h"

#include <algorithm>
#include <set>

#include <open3d/geometry/TriangleMesh.h>

#include "auv/recon/common/stage_error.h"
#include "auv/recon/scene/colmap_text.h"

namespace fs = std::filesystem;

namespace auv::recon::evaluate {
namespace {

constexpr const char* kStage = "evaluate";

View viewOf(const GroundTruth& truth, const GroundTruthFrame& frame) {
  View view;
  view.camera = truth.cameras().at(frame.image.camera_id);
  view.rotation_cw = frame.image.rotation();
  view.translation_cw = frame.image.t_cw;
  return view;
}

}  // namespace

SurveyAlignment alignSurveyToTruth(const Survey& survey, const GroundTruth& truth,
                                   const EvaluateOptions& options) {
  SurveyAlignment result;
  Survey::requireExists(survey.sparse() / "images.txt", kStage, "sfm");
  try {
    result.sparse = scene::readColmapText(survey.sparse());
  } catch (const std::exception& e) {
    throw StageError(kStage, std::string("sparse model: ") + e.what());
  }
  if (result.sparse.images.empty()) {
    throw StageError(kStage, survey.sparse().string() + ": no registered images");
  }
  if (fs::is_directory(survey.keyframes())) {
    result.sources = readKeyframeSources(survey.keyframes());
  }
  result.matching = matchImages(result.sparse, result.sources, truth);
  const ImageMatching& matching = result.matching;
  if (matching.matched.size() < 3) {
    std::string examples;
    for (size_t i = 0; i < std::min<size_t>(3, matching.unmatched.size()); ++i) {
      examples += (i ? ", " : "") + matching.unmatched[i];
    }
    throw StageError(kStage, "only " + std::to_string(matching.matched.size()) + " of " +
                                 std::to_string(result.sparse.images.size()) +
                                 " registered images match a ground-truth frame of " +
                                 truth.run().string() + " (unmatched: " + examples +
                                 "): is it the run these videos were rendered from?");
  }
  result.pairs = posePairs(matching, result.sparse);
  AlignmentOptions alignment_options;
  alignment_options.axis_length_m = options.axis_length_m;
  alignment_options.inlier_sigmas = options.inlier_sigmas;
  alignment_options.min_inlier_m = options.min_inlier_m;
  alignment_options.seed = static_cast<uint64_t>(options.seed);
  result.alignment = alignToTruth(result.pairs, alignment_options);
  if (result.alignment.status != AlignmentStatus::SUCCESS) {
    throw StageError(kStage, "alignment of " + survey.root().string() +
                                 " to the ground truth failed: " + result.alignment.message);
  }
  result.errors = poseErrors(result.pairs, result.alignment.similarity);
  return result;
}

std::vector<View> keyframeViews(const GroundTruth& truth, const SurveyAlignment& survey) {
  std::vector<View> views;
  std::set<std::string> keys;
  for (const auto& [camera, list] : survey.sources) {
    for (const KeyframeSource& source : list) {
      const GroundTruthFrame* frame = truth.find(source.key());
      if (frame && keys.insert(source.key()).second) views.push_back(viewOf(truth, *frame));
    }
  }
  for (const MatchedImage& m : survey.matching.matched) {  // no index: the registered images
    if (keys.insert(frameKey(m.truth->video, m.truth->frame)).second) {
      views.push_back(viewOf(truth, *m.truth));
    }
  }
  return views;
}

WellImagedSamples wellImagedRegion(const GroundTruth& truth, const std::vector<View>& views,
                                   const EvaluateOptions& options) {
  WellImagedOptions region_options;
  region_options.min_views = options.min_views;
  // Default range: half the visibility, where Koschmieder's contrast exp(-3.912 d / V) is
  // still 14 % (the simulator's rock fades into the water beyond it).
  region_options.max_range_m = options.max_range_m > 0  ? options.max_range_m
                               : truth.visibility() > 0 ? 0.5 * truth.visibility()
                                                        : kDefaultWellImagedRangeM;
  region_options.max_incidence_deg = options.max_incidence_deg;
  const auto mesh = truth.worldMesh();
  std::vector<Eigen::Vector3d> centers;
  for (const View& v : views) centers.push_back(v.center());
  const std::vector<size_t> near = trianglesNear(*mesh, centers, region_options.max_range_m);
  WellImagedSamples result;
  result.max_range_m = region_options.max_range_m;
  result.samples =
      sampleSurface(*mesh, options.sample_spacing_m, static_cast<uint64_t>(options.seed), &near);
  const OcclusionTester occlusion(*mesh);
  const std::vector<uint8_t> counts = countViews(result.samples, views, occlusion, region_options);
  result.well_imaged.resize(result.samples.size());
  for (size_t i = 0; i < result.samples.size(); ++i) {
    result.well_imaged[i] = counts[i] >= options.min_views;
    result.count += result.well_imaged[i] ? 1 : 0;
  }
  return result;
}

}  // namespace auv::recon::evaluate
