#include "auv/recon/features/match_plan.h"

#include <algorithm>
#include <atomic>
#include <fstream>
#include <iostream>
#include <numeric>
#include <random>
#include <sstream>
#include <thread>

#include <opencv2/core.hpp>

#include "auv/recon/calibration/calibration.h"
#include "auv/recon/common/progress.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/threads.h"
#include "auv/recon/common/trajectory.h"
#include "auv/recon/features/vocabulary.h"

namespace fs = std::filesystem;

namespace auv::recon::features {
namespace {

constexpr const char* kStage = "match";

int threadCount(int requested) { return matchThreads(requested); }

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

}  // namespace

int matchThreads(int requested) {
  if (requested > 0) return requested;
  return defaultThreadCount();
}

MatchPlan planMatches(const Survey& survey, const MatchStageOptions& options) {
  MatchPlan plan;
  const fs::path features_folder = survey.root() / "features";
  plan.store = std::make_unique<FeatureStore>(features_folder);
  const std::vector<FeatureIndexEntry>& entries = plan.store->images();
  if (entries.size() < 2) {
    throw StageError(kStage, features_folder.string() + "/index.csv lists " +
                                 std::to_string(entries.size()) +
                                 " image(s): at least 2 are needed");
  }
  const std::vector<TimedPosition> trajectory = readNavigation(survey, options, plan.navigation);
  plan.placed = placeImages(survey, entries, trajectory);
  if (!trajectory.empty()) {
    std::cout << "match: navigation " << plan.navigation.string() << ": " << plan.placed.placed
              << " of " << plan.placed.images.size()
              << " keyframes placed; appearance pairs at most " << options.pairs.loop_max_distance_m
              << " m apart" << std::endl;
  }
  // Appearance similarity for loop candidates (only where pairs are not exhaustive).
  plan.exhaustive = static_cast<int>(entries.size()) <= options.pairs.exhaustive_max_images;
  const cv::Mat similarity = !plan.exhaustive && options.pairs.loop_top_k > 0
                                 ? appearanceSimilarity(*plan.store, entries, options)
                                 : cv::Mat();
  plan.candidates = selectPairs(plan.placed.images, similarity, options.pairs);
  return plan;
}

}  // namespace auv::recon::features
