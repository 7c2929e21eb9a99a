#include "auv/recon/features/match_stage.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <limits>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <numeric>
#include <random>
#include <sstream>
#include <thread>
#include <unordered_map>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "auv/recon/calibration/calibration.h"
#include "auv/recon/common/option_set.h"
#include "auv/recon/common/progress.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/staged_output.h"
#include "auv/recon/common/trajectory.h"
#include "auv/recon/estimators/essential.h"
#include "auv/recon/estimators/fundamental.h"
#include "auv/recon/estimators/homography.h"
#include "auv/recon/features/match_output.h"
#include "auv/recon/features/match_plan.h"

namespace fs = std::filesystem;

namespace auv::recon::features {
namespace {

constexpr const char* kStage = "match";

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

struct IndexedFeatures {
  IndexedFeatures(ImageFeatures f, const MatchingOptions& options,
                  std::shared_ptr<const CascadeHashProjection> projection)
      : features(std::move(f)), index(features.descriptors, options, std::move(projection)) {}
  ImageFeatures features;
  DescriptorIndex index;
};

// A bounded cache of indexed images shared by the matching threads.
class FeatureCache {
 public:
  FeatureCache(const FeatureStore& store, const MatchingOptions& options,
               std::shared_ptr<const CascadeHashProjection> projection, size_t capacity)
      : store_(store), options_(options), projection_(std::move(projection)), capacity_(capacity) {}

  std::shared_ptr<const IndexedFeatures> get(const std::string& image) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      const auto it = entries_.find(image);
      if (it != entries_.end()) {
        order_.splice(order_.begin(), order_, it->second.second);
        return it->second.first;
      }
    }
    auto features =
        std::make_shared<const IndexedFeatures>(store_.read(image), options_, projection_);
    std::lock_guard<std::mutex> lock(mutex_);
    if (entries_.count(image) == 0) {
      order_.push_front(image);
      entries_[image] = {features, order_.begin()};
      while (entries_.size() > capacity_) {
        entries_.erase(order_.back());
        order_.pop_back();
      }
    }
    return features;
  }

 private:
  const FeatureStore& store_;
  const MatchingOptions& options_;
  std::shared_ptr<const CascadeHashProjection> projection_;
  size_t capacity_;
  std::mutex mutex_;
  std::list<std::string> order_;  // most recent first
  std::unordered_map<std::string, std::pair<std::shared_ptr<const IndexedFeatures>,
                                            std::list<std::string>::iterator>>
      entries_;
};

/// The hashing every image shares (search "cascade_hash"; else nullptr): centred on the mean
/// descriptor of up to 64 images spread over the survey, the same in every shard.
std::shared_ptr<const CascadeHashProjection> surveyProjection(const FeatureStore& store,
                                                              const std::vector<PairImage>& images,
                                                              const MatchingOptions& options) {
  if (options.search != "cascade_hash" || images.empty()) return nullptr;
  const size_t sampled = std::min<size_t>(64, images.size());
  std::vector<cv::Mat> sample;
  for (size_t i = 0; i < sampled; ++i) {
    sample.push_back(store.read(images[i * images.size() / sampled].name).descriptors);
  }
  return std::make_shared<const CascadeHashProjection>(meanDescriptor(sample), hashSeed(options));
}

}  // namespace

void VerificationOptions::check() const {
  AUV_RECON_CHECK_OPTION(min_inliers >= 8, min_inliers, "must be >= 8");
  AUV_RECON_CHECK_OPTION(max_threshold_px > 0, max_threshold_px, "must be > 0 px");
  AUV_RECON_CHECK_OPTION(max_iterations > 0, max_iterations, "must be > 0");
}

void MatchStageOptions::check() const {
  matching.check();
  pairs.check();
  verification.check();
  AUV_RECON_CHECK_OPTION(threads >= 0, threads, "must be >= 0 (0: all cores)");
}

void MatchStageOptions::bind(OptionSet& set) {
  set.add("ratio", &matching.ratio, "Lowe's ratio test: best < ratio x second best");
  set.add("mutual", &matching.mutual, "keep only mutual best matches");
  set.add("flann_above", &matching.flann_above,
          "images with more descriptors are searched approximately (search)");
  set.add("search", &matching.search,
          "approximate nearest neighbours: cascade_hash (Cheng et al. 2014) or kdtree (FLANN)");
  set.add("hash_candidates", &matching.hash_candidates,
          "cascade_hash: exact distances per query, for the closest codes");
  set.add("random_seed", &matching.random_seed,
          "random draw of the approximate search (hashing directions, forest trees)");
  set.add("flann_trees", &matching.flann_trees, "randomised k-d trees of a FLANN forest");
  set.add("flann_checks", &matching.flann_checks, "FLANN leaf checks");
  set.add("exhaustive_max_images", &pairs.exhaustive_max_images,
          "at most this many images: match every pair");
  set.add("sequential_window", &pairs.sequential_window,
          "next keyframes of the same camera matched with each keyframe");
  set.add("cross_camera_max_dt_s", &pairs.cross_camera_max_dt_s,
          "s: cross-camera pairs at most this far apart in sim_time_s (0: none)");
  set.add("loop_top_k", &pairs.loop_top_k, "most similar images matched per image (0: none)");
  set.add("loop_min_separation", &pairs.loop_min_separation,
          "same-camera keyframes closer than this are not loop candidates");
  set.add("loop_min_score", &pairs.loop_min_score,
          "appearance candidates need this fraction of the image's best similarity");
  set.add("loop_max_distance_m", &pairs.loop_max_distance_m,
          "m: appearance candidates at most this far apart by navigation (0: no limit)");
  set.add("navigation", &navigation,
          "TUM trajectory of the vehicle's navigation: keyframe positions (default: the "
          "survey's navigation.tum, if any)");
  set.add("vocabulary_words", &pairs.vocabulary_words, "visual words of the vocabulary");
  set.add("min_inliers", &verification.min_inliers, "pairs with fewer inliers are dropped");
  set.add("max_threshold_px", &verification.max_threshold_px,
          "px: upper bound of AC-RANSAC's adaptive threshold");
  set.add("max_iterations", &verification.max_iterations, "AC-RANSAC samples per pair");
  set.add("hopeless_exit", &verification.hopeless_exit,
          "stop a pair's AC-RANSAC once a model of min_inliers inliers would have been found "
          "(false: every pair draws max_iterations samples, as before issue 24)");
  set.add("estimate_homography", &verification.estimate_homography,
          "also count homography inliers (planarity of the pair)");
  set.add("force_fundamental", &verification.force_fundamental,
          "fundamental matrix even for calibrated cameras");
  set.add("threads", &threads, "pairs matched at once (0: all cores)");
}

VerifiedPair verifyPair(const PairGeometryInput& input, const VerificationOptions& options,
                        PairVerification* verification) {
  options.check();
  if (input.features1 == nullptr || input.features2 == nullptr) {
    throw std::invalid_argument("verifyPair: features of both images are required");
  }
  const ImageFeatures& f1 = *input.features1;
  const ImageFeatures& f2 = *input.features2;
  VerifiedPair pair;
  pair.image1 = f1.image;
  pair.image2 = f2.image;
  pair.putative = static_cast<uint32_t>(input.putative.size());
  std::vector<Eigen::Vector2d> x1, x2;
  x1.reserve(input.putative.size());
  x2.reserve(input.putative.size());
  for (const MatchIndices& m : input.putative) {
    if (m.first >= f1.size() || m.second >= f2.size()) {
      throw std::out_of_range("verifyPair: match (" + std::to_string(m.first) + ", " +
                              std::to_string(m.second) + ") outside " + f1.image + " / " +
                              f2.image);
    }
    x1.emplace_back(f1.keypoints[m.first].x, f1.keypoints[m.first].y);
    x2.emplace_back(f2.keypoints[m.second].x, f2.keypoints[m.second].y);
  }
  if (static_cast<int>(input.putative.size()) < options.min_inliers) return pair;

  estimators::AcRansacOptions ransac;
  ransac.max_iterations = options.max_iterations;
  ransac.max_threshold = options.max_threshold_px;
  if (options.hopeless_exit) ransac.min_inliers = options.min_inliers;
  const bool calibrated =
      input.camera1 != nullptr && input.camera2 != nullptr && !options.force_fundamental;
  const estimators::ImageSize size1{f1.width, f1.height}, size2{f2.width, f2.height};
  estimators::AcRansacResult<Eigen::Matrix3d> result;
  if (calibrated) {
    pair.kind = GeometryKind::ESSENTIAL;
    result = estimators::estimateEssential(x1, x2, *input.camera1, *input.camera2, ransac);
  } else {
    pair.kind = GeometryKind::FUNDAMENTAL;
    result = estimators::estimateFundamental(x1, x2, size1, size2, ransac);
  }
  pair.log10_nfa = result.log10_nfa;
  pair.threshold_px = result.threshold;
  if (verification != nullptr) {
    verification->iterations = result.iterations;
    verification->hopeless = result.hopeless;
  }
  if (!result.success() || static_cast<int>(result.numInliers()) < options.min_inliers) {
    return pair;
  }
  pair.model = result.model;
  if (options.estimate_homography) {
    const auto h = estimators::estimateHomography(x1, x2, size1, size2, ransac);
    pair.homography_inliers = h.success() ? static_cast<uint32_t>(h.numInliers()) : 0;
  }
  pair.inliers.reserve(result.numInliers());
  for (int i : result.inliers) pair.inliers.push_back(input.putative[i]);
  return pair;
}

namespace {

/// Matches and verifies every candidate pair on `threads` threads; the first error ends the
/// stage.
std::vector<PairOutcome> matchCandidates(const FeatureStore& store, const PlacedImages& placed,
                                         const std::vector<CandidatePair>& candidates,
                                         const MatchStageOptions& options, int threads) {
  const std::vector<PairImage>& images = placed.images;
  // Pairs are matched in the order of their images' times (else their indexes), so each
  // image's index is built about once: in the candidates' order, a camera's images meet the
  // other cameras' again long after they left the cache (1002 builds for 277 canyon keyframes
  // in that order, 284 in this one, with 48 images cached: ~5 MB each at 8000 descriptors).
  auto when = [&](int image) {
    return std::isnan(images[image].time_s) ? static_cast<double>(image) : images[image].time_s;
  };
  std::vector<size_t> order(candidates.size());
  std::iota(order.begin(), order.end(), size_t{0});
  auto key = [&](const CandidatePair& c) {
    const double a = when(c.index1), b = when(c.index2);
    return std::make_pair(std::min(a, b), std::max(a, b));
  };
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return key(candidates[a]) < key(candidates[b]); });
  FeatureCache cache(
      store, options.matching, surveyProjection(store, images, options.matching),
      static_cast<size_t>(std::max(48, 2 * options.pairs.sequential_window + 4 * threads)));
  std::vector<PairOutcome> outcomes(candidates.size());
  Progress progress("match", "pairs", candidates.size());
  std::mutex error_mutex;
  std::string first_error;
  std::atomic<size_t> next{0};
  auto worker = [&] {
    for (size_t n = next++; n < candidates.size(); n = next++) {
      const size_t i = order[n];
      try {
        const CandidatePair& c = candidates[i];
        const auto f1 = cache.get(images[c.index1].name);
        const auto f2 = cache.get(images[c.index2].name);
        PairGeometryInput input;
        input.features1 = &f1->features;
        input.features2 = &f2->features;
        input.camera1 = placed.cameras.at(images[c.index1].camera).get();
        input.camera2 = placed.cameras.at(images[c.index2].camera).get();
        input.putative = matchDescriptors(f1->index, f2->index, options.matching);
        PairOutcome& out = outcomes[i];
        out.pair = verifyPair(input, options.verification, &out.verification);
        out.pair.source = c.source;
        if (out.pair.putative < static_cast<uint32_t>(options.verification.min_inliers)) {
          out.status = "too_few_putative";
        } else if (out.verification.hopeless) {
          out.status = "hopeless";
        } else if (!(out.pair.log10_nfa < 0)) {
          out.status = "no_meaningful_model";
        } else if (out.pair.inliers.empty()) {
          out.status = "too_few_inliers";
        } else {
          out.status = "verified";
        }
      } catch (const std::exception& error) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (first_error.empty()) first_error = error.what();
        return;
      }
      progress.advance();
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::min<int>(threads, static_cast<int>(candidates.size())); ++t) {
    pool.emplace_back(worker);
  }
  worker();
  for (std::thread& t : pool) t.join();
  progress.finish();
  if (!first_error.empty()) throw StageError(kStage, first_error);
  return outcomes;
}

}  // namespace

MatchStageResult runMatchStage(const Survey& survey, const MatchStageOptions& options) {
  options.check();
  const auto start = std::chrono::steady_clock::now();
  const MatchPlan plan = planMatches(survey, options);
  const int threads = matchThreads(options.threads);
  std::vector<PairOutcome> outcomes =
      matchCandidates(*plan.store, plan.placed, plan.candidates, options, threads);
  std::vector<VerifiedPair> verified;
  const std::string csv = collectOutcomes(outcomes, plan.candidates, &verified);
  return writeMatches(survey, options, figuresOf(plan), verified, csv, secondsSince(start), threads,
                      1);
}

namespace {

/// FNV-1a of a file's bytes: the features a shard matched, compared at the merge.
std::string contentHash(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  uint64_t hash = 14695981039346656037ull;
  for (char c; in.get(c);) hash = (hash ^ static_cast<unsigned char>(c)) * 1099511628211ull;
  std::ostringstream hex;
  hex << std::hex << hash;
  return hex.str();
}

/// A JSON file's value; a discarded value when it is missing or not JSON.
nlohmann::json readJsonFile(const fs::path& file) {
  std::ifstream in(file);
  return nlohmann::json::parse(in, nullptr, false);
}

fs::path featureIndex(const Survey& survey) { return survey.root() / "features" / "index.csv"; }

/// What every shard computes alike and the merge needs instead of planning again (25-49 s on
/// the 277-keyframe canyon): the plan's figures, its candidates by name, the options and the
/// features it was made of. The merge refuses shards whose records differ.
nlohmann::json planRecord(const Survey& survey, const MatchStageOptions& options,
                          const MatchPlan& plan) {
  const PlanFigures figures = figuresOf(plan);
  nlohmann::json pairs = nlohmann::json::array();
  for (const CandidatePair& c : plan.candidates) {
    pairs.push_back({plan.placed.images[c.index1].name, plan.placed.images[c.index2].name});
  }
  return {{"images", figures.images},
          {"images_with_navigation", figures.images_with_navigation},
          {"exhaustive", figures.exhaustive},
          {"navigation", figures.navigation},
          {"options", optionsJson(options, figures.navigation)},
          {"features_index", contentHash(featureIndex(survey))},
          {"candidates", pairs}};
}

}  // namespace

size_t runMatchShard(const Survey& survey, const MatchStageOptions& options, Shard shard) {
  options.check();
  shard.check();
  const auto start = std::chrono::steady_clock::now();
  const MatchPlan plan = planMatches(survey, options);
  std::vector<CandidatePair> mine;  // candidates index, index + count, ...
  for (size_t i = static_cast<size_t>(shard.index); i < plan.candidates.size(); i += shard.count) {
    mine.push_back(plan.candidates[i]);
  }
  const int threads = matchThreads(options.threads);
  std::vector<PairOutcome> outcomes =
      mine.empty() ? std::vector<PairOutcome>{}
                   : matchCandidates(*plan.store, plan.placed, mine, options, threads);
  std::vector<VerifiedPair> verified;
  const std::string csv = collectOutcomes(outcomes, mine, &verified);
  StagedOutput output(shardFolder(survey, kStage, shard));
  writeVerifiedPairs(output.path() / "pairs.bin", verified);
  writeFileAtomically(output.path() / "rows.csv", csv);
  writeFileAtomically(output.path() / "plan.json", planRecord(survey, options, plan).dump());
  writeFileAtomically(
      output.path() / "shard.json",
      nlohmann::json{{"seconds", secondsSince(start)}, {"threads", threads}}.dump());
  output.commit();
  return mine.size();
}

MatchStageResult mergeMatchShards(const Survey& survey, const MatchStageOptions& options,
                                  int count) {
  options.check();
  struct ShardRows {
    std::vector<std::string> rows;
    std::vector<VerifiedPair> verified;
    size_t next_row = 0, next_pair = 0;
  };
  std::vector<ShardRows> shards(count);
  nlohmann::json plan;  // shard 0's record; every other shard's must equal it
  double seconds = 0;
  int threads = 1;
  for (int index = 0; index < count; ++index) {
    const fs::path folder = shardFolder(survey, kStage, {index, count});
    const std::string which = "shard " + std::to_string(index) + " of " + std::to_string(count);
    const std::string rerun = ": run the shards again";
    if (!fs::exists(folder / "shard.json")) {
      throw StageError(kStage, which + " has not run (`auv recon run " + survey.root().string() +
                                   " --from match --to match --shard " + std::to_string(index) +
                                   "/" + std::to_string(count) + "`)");
    }
    const nlohmann::json shard_report = readJsonFile(folder / "shard.json");
    const nlohmann::json record = readJsonFile(folder / "plan.json");
    if (!shard_report.is_object() || !record.is_object() || !record["candidates"].is_array()) {
      throw StageError(kStage, which + ": shard.json or plan.json is damaged" + rerun);
    }
    if (index == 0) {
      plan = record;
      if (plan.value("features_index", "") != contentHash(featureIndex(survey))) {
        throw StageError(kStage, which + " matched other features than " +
                                     featureIndex(survey).string() + " lists" + rerun);
      }
      if (plan["options"] != optionsJson(options, plan.value("navigation", ""))) {
        throw StageError(kStage, which + " ran with other match options than the merge" + rerun);
      }
    } else if (record != plan) {
      throw StageError(kStage, which +
                                   " matched another plan than shard 0 (the features or "
                                   "options changed between the shards)" +
                                   rerun);
    }
    seconds += shard_report.value("seconds", 0.0);
    threads = std::max(threads, shard_report.value("threads", 1));
    std::ifstream rows_in(folder / "rows.csv");
    for (std::string line; std::getline(rows_in, line);) shards[index].rows.push_back(line + "\n");
    shards[index].verified = readVerifiedPairs(folder / "pairs.bin");
  }
  // The candidates in their order: candidate i is row i / count of shard i % count, and the
  // shard's next verified pair when that pair is of the candidate's two images.
  const nlohmann::json& candidates = plan["candidates"];
  std::vector<VerifiedPair> verified;
  std::string csv;
  for (size_t i = 0; i < candidates.size(); ++i) {
    ShardRows& shard = shards[i % count];
    if (shard.next_row >= shard.rows.size()) {
      throw StageError(kStage, "shard " + std::to_string(i % count) + " of " +
                                   std::to_string(count) + " is short of rows: run it again");
    }
    csv += shard.rows[shard.next_row++];
    if (shard.next_pair < shard.verified.size() &&
        shard.verified[shard.next_pair].image1 == candidates[i][0] &&
        shard.verified[shard.next_pair].image2 == candidates[i][1]) {
      verified.push_back(std::move(shard.verified[shard.next_pair++]));
    }
  }
  for (int index = 0; index < count; ++index) {
    if (shards[index].next_pair != shards[index].verified.size()) {
      throw StageError(kStage, "shard " + std::to_string(index) +
                                   ": pairs.bin and rows.csv disagree: run it again");
    }
  }
  const PlanFigures figures{plan.value("images", size_t{0}),
                            plan.value("images_with_navigation", size_t{0}), candidates.size(),
                            plan.value("exhaustive", false), plan.value("navigation", "")};
  MatchStageResult result =
      writeMatches(survey, options, figures, verified, csv, seconds, threads, count);
  fs::remove_all(survey.root() / ".shards" / kStage);
  return result;
}

namespace {

StageReport reportOf(const Survey& survey, const MatchStageResult& result) {
  std::ostringstream line;
  line << "match: " << result.verified_pairs << " of " << result.candidate_pairs
       << " candidate pairs verified (" << result.essential_pairs << " essential, "
       << result.fundamental_pairs << " fundamental), " << result.verified_matches
       << " inlier matches over " << result.images << " images in " << result.seconds << " s -> "
       << (survey.root() / "features" / "matches").string();
  StageReport report;
  report.lines.push_back(line.str());
  report.summary = std::to_string(result.verified_pairs) + " of " +
                   std::to_string(result.candidate_pairs) + " pairs verified, " +
                   std::to_string(result.verified_matches) + " matches";
  return report;
}

}  // namespace

StageReport MatchStage::runWith(const Survey& survey, const MatchStageOptions& options) const {
  return reportOf(survey, runMatchStage(survey, options));
}

StageReport MatchStage::runShardWith(const Survey& survey, const MatchStageOptions& options,
                                     Shard shard) const {
  return shardReport("match", shard,
                     std::to_string(runMatchShard(survey, options, shard)) + " pairs");
}

StageReport MatchStage::mergeShardsWith(const Survey& survey, const MatchStageOptions& options,
                                        int count) const {
  return mergedReport(reportOf(survey, mergeMatchShards(survey, options, count)), count);
}

}  // namespace auv::recon::features
