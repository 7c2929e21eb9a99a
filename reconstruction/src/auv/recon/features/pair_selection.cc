#include "auv/recon/features/pair_selection.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

#include "auv/recon/common/stage_error.h"

namespace auv::recon::features {

void PairSelectionOptions::check() const {
  AUV_RECON_CHECK_OPTION(exhaustive_max_images >= 0, exhaustive_max_images, "must be >= 0");
  AUV_RECON_CHECK_OPTION(sequential_window >= 0, sequential_window, "must be >= 0");
  AUV_RECON_CHECK_OPTION(cross_camera_max_dt_s >= 0, cross_camera_max_dt_s, "must be >= 0 s");
  AUV_RECON_CHECK_OPTION(loop_top_k >= 0, loop_top_k, "must be >= 0");
  AUV_RECON_CHECK_OPTION(loop_min_separation >= 0, loop_min_separation, "must be >= 0");
  AUV_RECON_CHECK_OPTION(loop_min_score >= 0 && loop_min_score <= 1, loop_min_score,
                         "must be in [0, 1]");
  AUV_RECON_CHECK_OPTION(loop_max_distance_m >= 0, loop_max_distance_m, "must be >= 0 m");
  AUV_RECON_CHECK_OPTION(vocabulary_words >= 2, vocabulary_words, "must be >= 2");
}

std::vector<CandidatePair> selectPairs(const std::vector<PairImage>& images,
                                       const cv::Mat& similarity,
                                       const PairSelectionOptions& options) {
  options.check();
  const int n = static_cast<int>(images.size());
  if (!similarity.empty() &&
      (similarity.rows != n || similarity.cols != n || similarity.type() != CV_32F)) {
    throw std::invalid_argument("selectPairs: similarity must be " + std::to_string(n) + " x " +
                                std::to_string(n) + " CV_32F (is " +
                                std::to_string(similarity.rows) + " x " +
                                std::to_string(similarity.cols) + ")");
  }
  std::map<std::pair<int, int>, PairSource> chosen;  // first source wins
  auto add = [&](int a, int b, PairSource source) {
    if (a == b) return;
    chosen.emplace(std::make_pair(std::min(a, b), std::max(a, b)), source);
  };

  if (n <= options.exhaustive_max_images) {
    for (int a = 0; a < n; ++a) {
      for (int b = a + 1; b < n; ++b) add(a, b, PairSource::EXHAUSTIVE);
    }
  } else {
    // Sequential: per camera, by sequence.
    std::map<std::string, std::vector<int>> by_camera;
    for (int i = 0; i < n; ++i) by_camera[images[i].camera].push_back(i);
    for (auto& [camera, members] : by_camera) {
      std::sort(members.begin(), members.end(),
                [&](int a, int b) { return images[a].sequence < images[b].sequence; });
      for (size_t i = 0; i < members.size(); ++i) {
        for (size_t j = i + 1; j < members.size() && j <= i + options.sequential_window; ++j) {
          add(members[i], members[j], PairSource::SEQUENTIAL);
        }
      }
    }
    // Cross-camera by time.
    if (options.cross_camera_max_dt_s > 0) {
      for (int a = 0; a < n; ++a) {
        if (std::isnan(images[a].time_s)) continue;
        for (int b = a + 1; b < n; ++b) {
          if (images[a].camera == images[b].camera || std::isnan(images[b].time_s)) continue;
          if (std::abs(images[a].time_s - images[b].time_s) <= options.cross_camera_max_dt_s) {
            add(a, b, PairSource::CROSS_CAMERA);
          }
        }
      }
    }
    // Appearance: top-k most similar that are not sequential neighbours.
    if (!similarity.empty() && options.loop_top_k > 0) {
      for (int a = 0; a < n; ++a) {
        std::vector<std::pair<float, int>> ranked;
        const float* row = similarity.ptr<float>(a);
        for (int b = 0; b < n; ++b) {
          if (b == a) continue;
          const bool same_camera = images[a].camera == images[b].camera;
          if (same_camera &&
              std::abs(images[a].sequence - images[b].sequence) < options.loop_min_separation) {
            continue;
          }
          if (options.loop_max_distance_m > 0 && images[a].has_position && images[b].has_position &&
              (images[a].position - images[b].position).norm() > options.loop_max_distance_m) {
            continue;  // cannot share a view: a look-alike elsewhere
          }
          ranked.emplace_back(row[b], b);
        }
        const size_t k = std::min<size_t>(options.loop_top_k, ranked.size());
        std::partial_sort(ranked.begin(), ranked.begin() + k, ranked.end(),
                          [](const auto& x, const auto& y) {
                            return x.first > y.first || (x.first == y.first && x.second < y.second);
                          });
        if (k == 0 || !(ranked[0].first > 0)) continue;
        const float floor = static_cast<float>(options.loop_min_score) * ranked[0].first;
        for (size_t i = 0; i < k; ++i) {
          if (ranked[i].first < floor) break;
          const int b = ranked[i].second;
          add(a, b,
              images[a].camera == images[b].camera ? PairSource::LOOP : PairSource::CROSS_CAMERA);
        }
      }
    }
  }
  std::vector<CandidatePair> pairs;
  pairs.reserve(chosen.size());
  for (const auto& [key, source] : chosen) {
    pairs.push_back({key.first, key.second, source});
    if (!similarity.empty()) pairs.back().similarity = similarity.at<float>(key.first, key.second);
  }
  return pairs;
}

}  // namespace auv::recon::features
