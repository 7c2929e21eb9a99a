#pragma once
// Which pairs of images the match stage verifies (match_stage.h): the images in feature-index
// order with their camera, keyframe time and navigation position, and the candidate pairs of
// pair_selection.h (sequential, cross-camera, appearance loops gated by navigation). Every
// shard of a sharded match computes the same plan, so shard i takes candidates i, i + N, ...

#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "auv/recon/common/survey.h"
#include "auv/recon/features/feature_store.h"
#include "auv/recon/features/match_stage.h"
#include "auv/recon/features/pair_selection.h"
#include "auv/recon/scene/camera.h"

namespace auv::recon::features {

/// Threads for `requested` (0: the machine's cores).
int matchThreads(int requested);

/// The images with their camera order, times and navigation positions, and the cameras with
/// their calibration (nullptr: uncalibrated, a fundamental matrix).
struct PlacedImages {
  std::vector<PairImage> images;
  std::map<std::string, std::unique_ptr<scene::Camera>> cameras;
  size_t placed = 0;  // images with a navigation position
};

struct MatchPlan {
  std::unique_ptr<FeatureStore> store;
  PlacedImages placed;
  std::filesystem::path navigation;       ///< the trajectory read (empty: none)
  bool exhaustive = false;                ///< every pair (few images)
  std::vector<CandidatePair> candidates;  ///< each with its images' similarity, if computed
};

/// The plan of `survey`'s match stage; throws StageError (features missing, fewer than 2
/// images, unreadable navigation). Prints the navigation's use on stdout.
MatchPlan planMatches(const Survey& survey, const MatchStageOptions& options);

}  // namespace auv::recon::features
