#include "auv/recon/features/match_stage.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
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
#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/staged_output.h"
#include "auv/recon/common/trajectory.h"
#include "auv/recon/estimators/essential.h"
#include "auv/recon/estimators/fundamental.h"
#include "auv/recon/estimators/homography.h"
#include "auv/recon/features/vocabulary.h"

namespace fs = std::filesystem;

namespace auv::recon::features {
namespace {

constexpr const char* kStage = "match";

int threadCount(int requested) {
  if (requested > 0) return requested;
  return std::max(1u, std::thread::hardware_concurrency());
}

std::vector<std::string> splitCsv(const std::string& line) {
  std::vector<std::string> fields;
  std::string field;
  std::istringstream in(line);
  while (std::getline(in, field, ',')) fields.push_back(field);
  if (!line.empty() && line.back() == ',') fields.emplace_back();
  return fields;
}

// sim_time_s of each keyframe file of keyframes/<camera>/index.csv (the simulator's common
// clock; camera_time_s is per camera and not synchronised, so it is not used across cameras).
// Missing index or column: no times.
std::map<std::string, double> keyframeTimes(const fs::path& index_csv) {
  std::map<std::string, double> times;
  std::ifstream in(index_csv);
  std::string line;
  if (!in || !std::getline(in, line)) return times;
  const std::vector<std::string> header = splitCsv(line);
  const auto column = [&](const std::string& name) {
    const auto it = std::find(header.begin(), header.end(), name);
    return it == header.end() ? -1 : static_cast<int>(it - header.begin());
  };
  const int file = column("file"), sim = column("sim_time_s");
  if (file < 0 || sim < 0) return times;
  while (std::getline(in, line)) {
    const std::vector<std::string> f = splitCsv(line);
    if (static_cast<int>(f.size()) <= std::max(file, sim) || f[sim].empty()) continue;
    try {
      times[f[file]] = std::stod(f[sim]);
    } catch (const std::exception&) {
      // An unreadable time is an unknown time.
    }
  }
  return times;
}

// An image's features with their nearest-neighbour index, built once for all its pairs.
struct IndexedFeatures {
  IndexedFeatures(ImageFeatures f, const MatchingOptions& options)
      : features(std::move(f)), index(features.descriptors, options) {}
  ImageFeatures features;
  DescriptorIndex index;
};

// A bounded cache of indexed images shared by the matching threads.
class FeatureCache {
 public:
  FeatureCache(const FeatureStore& store, const MatchingOptions& options, size_t capacity)
      : store_(store), options_(options), capacity_(capacity) {}

  std::shared_ptr<const IndexedFeatures> get(const std::string& image) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      const auto it = entries_.find(image);
      if (it != entries_.end()) {
        order_.splice(order_.begin(), order_, it->second.second);
        return it->second.first;
      }
    }
    auto features = std::make_shared<const IndexedFeatures>(store_.read(image), options_);
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
  size_t capacity_;
  std::mutex mutex_;
  std::list<std::string> order_;  // most recent first
  std::unordered_map<std::string, std::pair<std::shared_ptr<const IndexedFeatures>,
                                            std::list<std::string>::iterator>>
      entries_;
};

struct PairOutcome {
  VerifiedPair pair;
  std::string status;
};

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
          "images with more descriptors are searched approximately (FLANN k-d forest)");
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
  set.add("estimate_homography", &verification.estimate_homography,
          "also count homography inliers (planarity of the pair)");
  set.add("force_fundamental", &verification.force_fundamental,
          "fundamental matrix even for calibrated cameras");
  set.add("threads", &threads, "pairs matched at once (0: all cores)");
}

VerifiedPair verifyPair(const PairGeometryInput& input, const VerificationOptions& options) {
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

/// The vehicle's navigation: the option, else the survey's navigation.tum when it has one;
/// `path` is set to the file read (empty: none).
std::vector<TimedPosition> readNavigation(const Survey& survey, const MatchStageOptions& options,
                                          fs::path& path) {
  path = options.navigation;
  if (path.empty() && fs::exists(survey.root() / "navigation.tum")) {
    path = survey.root() / "navigation.tum";
  }
  if (path.empty()) return {};
  try {
    return readTumTrajectory(path);
  } catch (const std::exception& e) {
    throw StageError(kStage, std::string("navigation: ") + e.what());
  }
}

/// The images with their camera order, times and navigation positions, and the cameras with
/// their calibration.
struct PlacedImages {
  std::vector<PairImage> images;
  std::map<std::string, std::unique_ptr<scene::Camera>> cameras;
  size_t placed = 0;  // images with a navigation position
};

PlacedImages placeImages(const Survey& survey, const std::vector<FeatureIndexEntry>& entries,
                         const std::vector<TimedPosition>& trajectory) {
  PlacedImages out;
  out.images.resize(entries.size());
  std::map<std::string, std::map<std::string, double>> times;
  std::map<std::string, int> next_sequence;
  for (size_t i = 0; i < entries.size(); ++i) {
    const FeatureIndexEntry& e = entries[i];
    if (!out.cameras.count(e.camera)) {
      // Without corrected/<camera>.yaml (uncalibrated images) the pair takes a fundamental
      // matrix instead of an essential one.
      const fs::path yaml = survey.corrected() / (e.camera + ".yaml");
      std::error_code error;
      out.cameras[e.camera] =
          fs::exists(yaml, error)
              ? std::make_unique<scene::Camera>(calibration::readUndistortedCamera(
                    yaml, static_cast<uint32_t>(out.cameras.size() + 1), kStage))
              : nullptr;
      times[e.camera] = keyframeTimes(survey.keyframes() / e.camera / "index.csv");
    }
    PairImage& image = out.images[i];
    image.name = e.image;
    image.camera = e.camera;
    image.sequence = next_sequence[e.camera]++;
    const std::string file = fs::path(e.image).filename().string();
    const auto t = times[e.camera].find(file);
    if (t != times[e.camera].end()) image.time_s = t->second;
    if (!trajectory.empty() && !std::isnan(image.time_s)) {
      image.has_position = positionAt(trajectory, image.time_s, image.position);
      if (image.has_position) ++out.placed;
    }
  }
  return out;
}

/// Appearance similarity of the images for loop candidates: tf-idf histograms over a
/// vocabulary trained on a sample of the descriptors. Empty when there are too few of them.
cv::Mat appearanceSimilarity(const FeatureStore& store,
                             const std::vector<FeatureIndexEntry>& entries,
                             const MatchStageOptions& options) {
  constexpr int kTrainingRows = 30000;
  const int per_image = std::max(1, kTrainingRows / static_cast<int>(entries.size()));
  std::mt19937_64 random(7);
  cv::Mat training;
  {
    Progress progress("match: vocabulary sample", "images", entries.size());
    for (const FeatureIndexEntry& e : entries) {
      const ImageFeatures f = store.read(e.image);
      std::vector<int> rows(f.size());
      std::iota(rows.begin(), rows.end(), 0);
      std::shuffle(rows.begin(), rows.end(), random);
      for (int r = 0; r < std::min<int>(per_image, static_cast<int>(rows.size())); ++r) {
        training.push_back(f.descriptors.row(rows[r]));
      }
      progress.advance();
    }
  }
  if (training.rows < options.pairs.vocabulary_words) return cv::Mat();
  const Vocabulary vocabulary = Vocabulary::train(training, options.pairs.vocabulary_words);
  std::vector<cv::Mat> histograms(entries.size());
  Progress progress("match: global descriptors", "images", entries.size());
  std::atomic<size_t> next{0};
  auto worker = [&] {
    for (size_t i = next++; i < entries.size(); i = next++) {
      histograms[i] = vocabulary.histogram(store.read(entries[i].image).descriptors);
      progress.advance();
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threadCount(options.threads); ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  return Vocabulary::similarity(Vocabulary::tfIdf(histograms));
}

/// Matches and verifies every candidate pair on `threads` threads; the first error ends the
/// stage.
std::vector<PairOutcome> matchCandidates(const FeatureStore& store, const PlacedImages& placed,
                                         const std::vector<CandidatePair>& candidates,
                                         const MatchStageOptions& options, int threads) {
  const std::vector<PairImage>& images = placed.images;
  FeatureCache cache(
      store, options.matching,
      static_cast<size_t>(std::max(16, 2 * options.pairs.sequential_window + 4 * threads)));
  std::vector<PairOutcome> outcomes(candidates.size());
  Progress progress("match", "pairs", candidates.size());
  std::mutex error_mutex;
  std::string first_error;
  std::atomic<size_t> next{0};
  auto worker = [&] {
    for (size_t i = next++; i < candidates.size(); i = next++) {
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
        out.pair = verifyPair(input, options.verification);
        out.pair.source = c.source;
        if (out.pair.putative < static_cast<uint32_t>(options.verification.min_inliers)) {
          out.status = "too_few_putative";
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
  const fs::path features_folder = survey.root() / "features";
  const FeatureStore store(features_folder);
  const std::vector<FeatureIndexEntry>& entries = store.images();
  if (entries.size() < 2) {
    throw StageError(kStage, features_folder.string() + "/index.csv lists " +
                                 std::to_string(entries.size()) +
                                 " image(s): at least 2 are needed");
  }
  fs::path navigation;
  const std::vector<TimedPosition> trajectory = readNavigation(survey, options, navigation);
  const PlacedImages placed = placeImages(survey, entries, trajectory);
  const size_t images_placed = placed.placed;
  if (!trajectory.empty()) {
    std::cout << "match: navigation " << navigation.string() << ": " << images_placed << " of "
              << placed.images.size() << " keyframes placed; appearance pairs at most "
              << options.pairs.loop_max_distance_m << " m apart" << std::endl;
  }
  // Appearance similarity for loop candidates (only where pairs are not exhaustive).
  const bool exhaustive = static_cast<int>(entries.size()) <= options.pairs.exhaustive_max_images;
  const cv::Mat similarity = !exhaustive && options.pairs.loop_top_k > 0
                                 ? appearanceSimilarity(store, entries, options)
                                 : cv::Mat();
  const std::vector<CandidatePair> candidates =
      selectPairs(placed.images, similarity, options.pairs);
  const int threads = threadCount(options.threads);
  std::vector<PairOutcome> outcomes = matchCandidates(store, placed, candidates, options, threads);

  MatchStageResult summary;
  summary.images = entries.size();
  summary.candidate_pairs = candidates.size();
  std::vector<VerifiedPair> verified;
  std::map<std::string, size_t> by_source;
  std::ostringstream csv;
  csv << "image1,image2,source,kind,putative,inliers,homography_inliers,log10_nfa,threshold_px,"
         "status\n";
  for (PairOutcome& o : outcomes) {
    const VerifiedPair& p = o.pair;
    csv << p.image1 << "," << p.image2 << "," << pairSourceName(p.source) << ","
        << geometryKindName(p.kind) << "," << p.putative << "," << p.inliers.size() << ","
        << p.homography_inliers << "," << p.log10_nfa << "," << p.threshold_px << "," << o.status
        << "\n";
    if (o.pair.inliers.empty()) continue;
    ++by_source[pairSourceName(p.source)];
    summary.verified_matches += p.inliers.size();
    (p.kind == GeometryKind::ESSENTIAL ? summary.essential_pairs : summary.fundamental_pairs)++;
    verified.push_back(std::move(o.pair));
  }
  summary.verified_pairs = verified.size();
  if (verified.empty()) {
    throw StageError(kStage, "no pair of the " + std::to_string(candidates.size()) +
                                 " candidates verified (at least " +
                                 std::to_string(options.verification.min_inliers) +
                                 " geometric inliers needed); earlier matches kept");
  }

  StagedOutput output(features_folder / "matches");
  writeVerifiedPairs(output.path() / "pairs.bin", verified);
  writeFileAtomically(output.path() / "pairs.csv", csv.str());
  output.commit();
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  nlohmann::json sources = nlohmann::json::object();
  for (const auto& [source, count] : by_source) sources[source] = count;
  updateReport(survey.report(), kStage,
               {{"images", summary.images},
                {"images_with_navigation", images_placed},
                {"candidate_pairs", summary.candidate_pairs},
                {"verified_pairs", summary.verified_pairs},
                {"verified_pairs_by_source", sources},
                {"verified_matches", summary.verified_matches},
                {"essential_pairs", summary.essential_pairs},
                {"fundamental_pairs", summary.fundamental_pairs},
                {"exhaustive", exhaustive},
                {"seconds", summary.seconds},
                {"threads", threads},
                {"options",
                 {{"ratio", options.matching.ratio},
                  {"mutual", options.matching.mutual},
                  {"flann_above", options.matching.flann_above},
                  {"flann_trees", options.matching.flann_trees},
                  {"flann_checks", options.matching.flann_checks},
                  {"sequential_window", options.pairs.sequential_window},
                  {"exhaustive_max_images", options.pairs.exhaustive_max_images},
                  {"cross_camera_max_dt_s", options.pairs.cross_camera_max_dt_s},
                  {"loop_top_k", options.pairs.loop_top_k},
                  {"loop_max_distance_m", options.pairs.loop_max_distance_m},
                  {"navigation", navigation.string()},
                  {"min_inliers", options.verification.min_inliers},
                  {"max_threshold_px", options.verification.max_threshold_px}}}});
  return summary;
}

StageReport MatchStage::runWith(const Survey& survey, const MatchStageOptions& options) const {
  const MatchStageResult result = runMatchStage(survey, options);
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

}  // namespace auv::recon::features
