#pragma once
// What the match stage writes (match_stage.h): features/matches/pairs.bin of the verified pairs,
// pairs.csv with a row per candidate pair, and the stage's section of report.json. Shared by the
// whole run and the merge of a sharded one.

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "auv/recon/common/survey.h"
#include "auv/recon/features/match_plan.h"
#include "auv/recon/features/match_stage.h"

namespace auv::recon::features {

/// How one candidate pair went.
struct PairOutcome {
  VerifiedPair pair;   ///< inliers empty: not verified
  std::string status;  ///< pairs.csv's `status`
  PairVerification verification;
};

/// pairs.csv's rows of `outcomes` (of `candidates`, in order); their verified pairs moved to
/// `verified`.
std::string collectOutcomes(std::vector<PairOutcome>& outcomes,
                            const std::vector<CandidatePair>& candidates,
                            std::vector<VerifiedPair>* verified);

/// What report.json says of the plan; a sharded match's merge reads it from the shards.
struct PlanFigures {
  size_t images = 0, images_with_navigation = 0, candidates = 0;
  bool exhaustive = false;
  std::string navigation;
};
PlanFigures figuresOf(const MatchPlan& plan);

/// The options as report.json records them (`navigation`: the trajectory the plan read).
nlohmann::json optionsJson(const MatchStageOptions& options, const std::string& navigation);

/// features/matches/ (staged: earlier matches stay whole until the new ones are complete) and
/// the `match` section of report.json. Throws StageError when `verified` is empty.
MatchStageResult writeMatches(const Survey& survey, const MatchStageOptions& options,
                              const PlanFigures& plan, const std::vector<VerifiedPair>& verified,
                              const std::string& csv, double seconds, int threads, int shards);

}  // namespace auv::recon::features
