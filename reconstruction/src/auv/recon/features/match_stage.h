#pragma once
// `auv recon match <survey>`: candidate pairs (pair_selection.h), descriptor matching with
// Lowe's ratio test and a mutual check (descriptor_matcher.h), geometric verification of each
// pair with AC-RANSAC (paper section 3.4.1): essential matrix when both cameras are calibrated
// (corrected/<camera>.yaml), else the fundamental matrix. Writes features/matches/ (match_store.h).

#include <filesystem>
#include <string>
#include <vector>

#include "auv/recon/common/stage.h"
#include "auv/recon/common/survey.h"
#include "auv/recon/estimators/ac_ransac.h"
#include "auv/recon/features/descriptor_matcher.h"
#include "auv/recon/features/feature_store.h"
#include "auv/recon/features/match_store.h"
#include "auv/recon/features/pair_selection.h"
#include "auv/recon/scene/camera.h"

namespace auv::recon {
class OptionSet;
}

namespace auv::recon::features {

struct VerificationOptions {
  /// Pairs with fewer geometric inliers are dropped.
  int min_inliers = 30;
  /// Upper bound of AC-RANSAC's adaptive threshold, px.
  double max_threshold_px = 4.0;
  /// AC-RANSAC minimal samples per pair.
  int max_iterations = 4096;
  /// Stop a pair's AC-RANSAC after the samples that would have drawn a model of min_inliers
  /// inliers with 99 % confidence, and never score a model with fewer (ac_ransac.h): the exit
  /// of pairs that cannot verify. false: every failing pair draws max_iterations samples.
  bool hopeless_exit = true;
  /// Also fit a homography to record homography_inliers (planarity of the pair).
  bool estimate_homography = true;
  /// Use the fundamental matrix even when both cameras are calibrated.
  bool force_fundamental = false;

  void check() const;
};

/// Verifies one pair of putative matches. Returns the verified pair or, when it fails, an
/// empty inlier list (the caller drops it). `calibrated`: both cameras pinhole-calibrated.
struct PairGeometryInput {
  const ImageFeatures* features1 = nullptr;
  const ImageFeatures* features2 = nullptr;
  const scene::Camera* camera1 = nullptr;  ///< nullptr: uncalibrated
  const scene::Camera* camera2 = nullptr;
  std::vector<MatchIndices> putative;
};
/// How verification went, for pairs.csv.
struct PairVerification {
  int iterations = 0;     ///< AC-RANSAC samples drawn (0: not verified, too few putatives)
  bool hopeless = false;  ///< stopped at the min_inliers bound (VerificationOptions)
};
VerifiedPair verifyPair(const PairGeometryInput& input, const VerificationOptions& options,
                        PairVerification* verification = nullptr);

struct MatchStageOptions {
  MatchingOptions matching;
  PairSelectionOptions pairs;
  VerificationOptions verification;
  /// TUM trajectory of the vehicle's navigation (e.g. <run>/ground_truth/navigation.tum): gives
  /// each keyframe (by sim_time_s) a position, and appearance pairs farther apart than
  /// pairs.loop_max_distance_m are not matched. Empty: <survey>/navigation.tum if it exists,
  /// else no navigation.
  std::string navigation;
  /// Pairs matched at once (0: the machine's cores).
  int threads = 0;

  void check() const;
  void bind(OptionSet& set);
};

struct MatchStageResult {
  size_t images = 0;
  size_t candidate_pairs = 0;
  size_t verified_pairs = 0;
  size_t verified_matches = 0;
  size_t essential_pairs = 0, fundamental_pairs = 0;
  double seconds = 0;
};

/// Reads features/ (FeatureStore), selects, matches and verifies pairs and writes
/// features/matches/ (StagedOutput) and the `match` section of report.json. Throws StageError
/// naming what is missing (features/, a feature file) or when no pair verifies.
MatchStageResult runMatchStage(const Survey& survey, const MatchStageOptions& options);

/// Shard `shard` of a sharded match (cluster/README.md): candidate pairs shard.index,
/// shard.index + shard.count, ... of the plan every shard computes alike (match_plan.h), into
/// shardFolder(survey, "match", shard). Returns the pairs matched.
size_t runMatchShard(const Survey& survey, const MatchStageOptions& options, Shard shard);

/// features/matches/ from the `count` shards' folders, the same files as runMatchStage writes;
/// the shards' folders are removed after. Throws StageError naming a shard that has not run or
/// matched another set of candidates.
MatchStageResult mergeMatchShards(const Survey& survey, const MatchStageOptions& options,
                                  int count);

/// The `match` stage (common/stage.h): `auv recon match` and a step of `auv recon run`.
class MatchStage final : public StageWith<MatchStageOptions> {
 public:
  std::string name() const override { return "match"; }
  std::string usage() const override {
    return "<survey>   match and verify image pairs (AC-RANSAC)";
  }
  std::string surveyHelp() const override {
    return "survey folder (reads features/, writes features/matches/)";
  }
  std::vector<std::filesystem::path> inputs(const Survey& survey) const override {
    return {survey.root() / "features" / "index.csv"};
  }
  std::vector<std::filesystem::path> outputs(const Survey& survey) const override {
    return {survey.root() / "features" / "matches"};
  }
  StageReport runWith(const Survey& survey, const MatchStageOptions& options) const override;
  bool shardable() const override { return true; }
  StageReport runShardWith(const Survey& survey, const MatchStageOptions& options,
                           Shard shard) const override;
  StageReport mergeShardsWith(const Survey& survey, const MatchStageOptions& options,
                              int count) const override;
};

}  // namespace auv::recon::features
