#pragma once
// One survey's reconstruction set against its simulated run: the registered images matched to
// their true frames, the similarity reconstruction -> truth with the camera errors after it,
// and the well-imaged region of the true surface seen from the survey's keyframes. Steps 1-3 of
// `auv recon evaluate` (evaluator.h), also run on the earlier survey of a comparison to bring
// its change points into the world frame (change_evaluation.h).

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "auv/recon/common/survey.h"
#include "auv/recon/evaluate/alignment.h"
#include "auv/recon/evaluate/evaluator.h"
#include "auv/recon/evaluate/ground_truth.h"
#include "auv/recon/evaluate/image_matching.h"
#include "auv/recon/evaluate/well_imaged_region.h"
#include "auv/recon/scene/reconstruction.h"

namespace auv::recon::evaluate {

/// m: well-imaged range when neither the option nor the scenario's visibility gives one (half
/// the paper's visibility in the canyon, section 4.3).
constexpr double kDefaultWellImagedRangeM = 2.25;

struct SurveyAlignment {
  scene::Reconstruction sparse;
  std::map<std::string, std::vector<KeyframeSource>> sources;  ///< keyframes per camera
  ImageMatching matching;  ///< points into the GroundTruth it was matched with
  std::vector<PosePair> pairs;
  AlignmentResult alignment;  ///< status SUCCESS (else alignSurveyToTruth throws)
  PoseErrors errors;
};

/// Reads the survey's sparse model and keyframe indexes, matches the images to `truth` and
/// aligns. Throws StageError("evaluate", ...): no sparse model, fewer than 3 images matching
/// the truth (naming the first unmatched), an alignment that fails.
SurveyAlignment alignSurveyToTruth(const Survey& survey, const GroundTruth& truth,
                                   const EvaluateOptions& options);

/// The true views of the survey's keyframes (every row of the indexes; without indexes, the
/// registered images'), each frame once.
std::vector<View> keyframeViews(const GroundTruth& truth, const SurveyAlignment& survey);

struct WellImagedSamples {
  SurfaceSamples samples;         ///< the true surface near the keyframes
  std::vector<bool> well_imaged;  ///< per sample
  size_t count = 0;               ///< samples well imaged
  double max_range_m = 0;         ///< the range used
};

/// The well-imaged region of `truth`'s world mesh seen from `views` (README.md, step 3): the
/// range is options.max_range_m, else half the water's visibility, else the default.
WellImagedSamples wellImagedRegion(const GroundTruth& truth, const std::vector<View>& views,
                                   const EvaluateOptions& options);

}  // namespace auv::recon::evaluate
