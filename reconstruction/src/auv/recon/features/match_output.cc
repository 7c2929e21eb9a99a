#include "auv/recon/features/match_output.h"

#include <cmath>
#include <map>
#include <sstream>

#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/staged_output.h"

namespace auv::recon::features {
namespace {

constexpr const char* kStage = "match";

constexpr const char* kCsvHeader =
    "image1,image2,source,kind,putative,inliers,homography_inliers,log10_nfa,threshold_px,status,"
    "iterations,similarity\n";

/// One line of pairs.csv: the outcome of candidate `c`.
std::string csvRow(const PairOutcome& o, const CandidatePair& c) {
  const VerifiedPair& p = o.pair;
  std::ostringstream row;
  row << p.image1 << "," << p.image2 << "," << pairSourceName(p.source) << ","
      << geometryKindName(p.kind) << "," << p.putative << "," << p.inliers.size() << ","
      << p.homography_inliers << "," << p.log10_nfa << "," << p.threshold_px << "," << o.status
      << "," << o.verification.iterations << ",";
  if (!std::isnan(c.similarity)) row << c.similarity;
  row << "\n";
  return row.str();
}

}  // namespace

std::string collectOutcomes(std::vector<PairOutcome>& outcomes,
                            const std::vector<CandidatePair>& candidates,
                            std::vector<VerifiedPair>* verified) {
  std::string csv;
  for (size_t i = 0; i < outcomes.size(); ++i) {
    csv += csvRow(outcomes[i], candidates[i]);
    if (!outcomes[i].pair.inliers.empty()) verified->push_back(std::move(outcomes[i].pair));
  }
  return csv;
}

PlanFigures figuresOf(const MatchPlan& plan) {
  return {plan.store->images().size(), plan.placed.placed, plan.candidates.size(), plan.exhaustive,
          plan.navigation.string()};
}

nlohmann::json optionsJson(const MatchStageOptions& options, const std::string& navigation) {
  return {{"ratio", options.matching.ratio},
          {"mutual", options.matching.mutual},
          {"flann_above", options.matching.flann_above},
          {"flann_trees", options.matching.flann_trees},
          {"flann_checks", options.matching.flann_checks},
          {"search", options.matching.search},
          {"hash_candidates", options.matching.hash_candidates},
          {"random_seed", options.matching.random_seed},
          {"sequential_window", options.pairs.sequential_window},
          {"exhaustive_max_images", options.pairs.exhaustive_max_images},
          {"cross_camera_max_dt_s", options.pairs.cross_camera_max_dt_s},
          {"loop_top_k", options.pairs.loop_top_k},
          {"loop_max_distance_m", options.pairs.loop_max_distance_m},
          {"navigation", navigation},
          {"min_inliers", options.verification.min_inliers},
          {"max_threshold_px", options.verification.max_threshold_px}};
}

MatchStageResult writeMatches(const Survey& survey, const MatchStageOptions& options,
                              const PlanFigures& plan, const std::vector<VerifiedPair>& verified,
                              const std::string& csv, double seconds, int threads, int shards) {
  MatchStageResult summary;
  summary.images = plan.images;
  summary.candidate_pairs = plan.candidates;
  summary.verified_pairs = verified.size();
  std::map<std::string, size_t> by_source;
  for (const VerifiedPair& p : verified) {
    ++by_source[pairSourceName(p.source)];
    summary.verified_matches += p.inliers.size();
    (p.kind == GeometryKind::ESSENTIAL ? summary.essential_pairs : summary.fundamental_pairs)++;
  }
  if (verified.empty()) {
    throw StageError(kStage, "no pair of the " + std::to_string(plan.candidates) +
                                 " candidates verified (at least " +
                                 std::to_string(options.verification.min_inliers) +
                                 " geometric inliers needed); earlier matches kept");
  }
  StagedOutput output(survey.root() / "features" / "matches");
  writeVerifiedPairs(output.path() / "pairs.bin", verified);
  writeFileAtomically(output.path() / "pairs.csv", kCsvHeader + csv);
  output.commit();
  summary.seconds = seconds;

  nlohmann::json sources = nlohmann::json::object();
  for (const auto& [source, count] : by_source) sources[source] = count;
  nlohmann::json report = {{"images", summary.images},
                           {"images_with_navigation", plan.images_with_navigation},
                           {"candidate_pairs", summary.candidate_pairs},
                           {"verified_pairs", summary.verified_pairs},
                           {"verified_pairs_by_source", sources},
                           {"verified_matches", summary.verified_matches},
                           {"essential_pairs", summary.essential_pairs},
                           {"fundamental_pairs", summary.fundamental_pairs},
                           {"exhaustive", plan.exhaustive},
                           {"seconds", summary.seconds},
                           {"threads", threads},
                           {"options", optionsJson(options, plan.navigation)}};
  if (shards > 1) report["shards"] = shards;
  updateReport(survey.report(), kStage, report);
  return summary;
}

}  // namespace auv::recon::features
