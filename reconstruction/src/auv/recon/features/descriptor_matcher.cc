#include "auv/recon/features/descriptor_matcher.h"

#include <algorithm>
#include <numeric>
#include <stdexcept>
#include <string>

#include "auv/recon/common/stage_error.h"

namespace auv::recon::features {

void MatchingOptions::check() const {
  AUV_RECON_CHECK_OPTION(ratio > 0 && ratio <= 1, ratio, "must be in (0, 1]");
  AUV_RECON_CHECK_OPTION(flann_above >= 0, flann_above, "must be >= 0");
  AUV_RECON_CHECK_OPTION(flann_trees > 0, flann_trees, "must be > 0");
  AUV_RECON_CHECK_OPTION(flann_checks > 0, flann_checks, "must be > 0");
  AUV_RECON_CHECK_OPTION(search == "cascade_hash" || search == "kdtree", search,
                         "must be cascade_hash or kdtree");
  AUV_RECON_CHECK_OPTION(hash_candidates >= 2, hash_candidates, "must be >= 2");
  AUV_RECON_CHECK_OPTION(random_seed >= 0, random_seed, "must be >= 0");
}

uint64_t hashSeed(const MatchingOptions& options) {
  return 0xCA5CADE ^ static_cast<uint64_t>(options.random_seed);
}

DescriptorIndex::DescriptorIndex(const cv::Mat& descriptors, const MatchingOptions& options,
                                 std::shared_ptr<const CascadeHashProjection> projection)
    : checks_(options.flann_checks), hash_candidates_(options.hash_candidates) {
  options.check();
  if (!descriptors.empty() && descriptors.type() != CV_8U && descriptors.type() != CV_32F) {
    throw std::invalid_argument("DescriptorIndex: descriptors of type " +
                                std::to_string(descriptors.type()) + " (CV_8U or CV_32F expected)");
  }
  if (descriptors.type() == CV_32F) {
    descriptors_ = descriptors;
  } else {
    descriptors.convertTo(descriptors_, CV_32F);
  }
  approximate_ = descriptors_.rows > options.flann_above;
  if (options.search == "cascade_hash") {
    if (projection == nullptr && !descriptors_.empty()) {
      projection = std::make_shared<CascadeHashProjection>(meanDescriptor({descriptors_}),
                                                           hashSeed(options));
    }
    if (projection != nullptr && projection->width() != descriptors_.cols &&
        !descriptors_.empty()) {
      throw std::invalid_argument("DescriptorIndex: descriptors of " +
                                  std::to_string(descriptors_.cols) + " columns, hashing of " +
                                  std::to_string(projection->width()));
    }
    projection_ = std::move(projection);
    if (projection_ != nullptr) {
      hashed_ = std::make_shared<const HashedDescriptors>(projection_->hash(descriptors_));
    }
  } else if (approximate_) {
    // The forest's trees are random (FLANN draws from this thread's cv::theRNG()): one seed per
    // build makes an image's index, and so its matches, the same in every run and every shard
    // of a sharded match, whichever thread builds it after whatever else.
    cv::theRNG() = cv::RNG(0x5eed ^ static_cast<uint64_t>(options.random_seed));
    forest_ = std::make_shared<cv::flann::Index>(
        descriptors_, cv::flann::KDTreeIndexParams(options.flann_trees), cvflann::FLANN_DIST_L2);
  }
}

void DescriptorIndex::knn(const DescriptorIndex& queries, const std::vector<int>& rows, int k,
                          cv::Mat* indices, cv::Mat* distances) const {
  if (approximate_ && hashed_ != nullptr) {
    if (queries.projection_ != projection_) {
      throw std::invalid_argument("DescriptorIndex: two indexes hashed by different projections");
    }
    cascadeHashKnn(descriptors_, *hashed_, queries.descriptors_, *queries.hashed_, rows, k,
                   hash_candidates_, indices, distances);
    return;
  }
  // Every row in order (the forward search of a pair) is the matrix itself: no 4 MB copy.
  bool all_rows = static_cast<int>(rows.size()) == queries.rows();
  for (size_t i = 0; all_rows && i < rows.size(); ++i) all_rows = rows[i] == static_cast<int>(i);
  cv::Mat query_rows = queries.descriptors_;
  if (!all_rows) {
    query_rows = cv::Mat(static_cast<int>(rows.size()), queries.cols(), CV_32F);  // a new one
    for (size_t i = 0; i < rows.size(); ++i) {
      queries.descriptors_.row(rows[i]).copyTo(query_rows.row(static_cast<int>(i)));
    }
  }
  if (forest_ != nullptr) {
    // FLANN's L2 distances are squared.
    forest_->knnSearch(query_rows, *indices, *distances, k, cv::flann::SearchParams(checks_));
    cv::sqrt(*distances, *distances);
    return;
  }
  // Exact: OpenCV's vectorised distances with a k-best selection (what cv::BFMatcher runs).
  cv::batchDistance(query_rows, descriptors_, *distances, CV_32F, *indices, cv::NORM_L2,
                    std::min(k, descriptors_.rows));
}

std::vector<MatchIndices> matchDescriptors(const DescriptorIndex& index1,
                                           const DescriptorIndex& index2,
                                           const MatchingOptions& options) {
  options.check();
  if (index1.rows() == 0 || index2.rows() == 0) return {};
  if (index1.cols() != index2.cols()) {
    throw std::invalid_argument("matchDescriptors: descriptors of different widths (" +
                                std::to_string(index1.cols()) + " and " +
                                std::to_string(index2.cols()) + " columns)");
  }
  if (index2.rows() < 2) return {};  // no second neighbour: the ratio test cannot pass
  std::vector<int> rows1(index1.rows());
  std::iota(rows1.begin(), rows1.end(), 0);
  cv::Mat nearest, distance;
  index2.knn(index1, rows1, 2, &nearest, &distance);
  std::vector<MatchIndices> matches;
  for (int row = 0; row < nearest.rows; ++row) {
    const int* n = nearest.ptr<int>(row);
    const float* d = distance.ptr<float>(row);
    if (n[0] < 0 || n[1] < 0) continue;
    // Lowe's test on distances (not squared): d1 < ratio * d2.
    if (!(d[0] < options.ratio * d[1])) continue;
    matches.emplace_back(static_cast<uint32_t>(row), static_cast<uint32_t>(n[0]));
  }
  if (options.mutual && !matches.empty()) {
    // Best match back into image 1, only for the rows of image 2 that were matched (the same
    // answer as matching all of image 2 back, at a fraction of the cost).
    std::vector<int> rows2;
    for (const MatchIndices& m : matches) rows2.push_back(static_cast<int>(m.second));
    std::sort(rows2.begin(), rows2.end());
    rows2.erase(std::unique(rows2.begin(), rows2.end()), rows2.end());
    cv::Mat back, back_distance;
    index1.knn(index2, rows2, 1, &back, &back_distance);
    std::vector<int> best_back(index2.rows(), -1);
    for (size_t i = 0; i < rows2.size(); ++i)
      best_back[rows2[i]] = back.at<int>(static_cast<int>(i), 0);
    matches.erase(std::remove_if(matches.begin(), matches.end(),
                                 [&](const MatchIndices& m) {
                                   return best_back[m.second] != static_cast<int>(m.first);
                                 }),
                  matches.end());
  }
  std::sort(matches.begin(), matches.end());
  return matches;
}

std::vector<MatchIndices> matchDescriptors(const cv::Mat& descriptors1, const cv::Mat& descriptors2,
                                           const MatchingOptions& options) {
  options.check();
  if (descriptors1.empty() || descriptors2.empty()) return {};
  if (descriptors1.cols != descriptors2.cols || descriptors1.type() != descriptors2.type() ||
      (descriptors1.type() != CV_8U && descriptors1.type() != CV_32F)) {
    throw std::invalid_argument("matchDescriptors: descriptors of different widths or types (" +
                                std::to_string(descriptors1.cols) + " and " +
                                std::to_string(descriptors2.cols) +
                                " columns; CV_8U or CV_32F expected)");
  }
  std::shared_ptr<const CascadeHashProjection> projection;
  if (options.search == "cascade_hash") {
    projection = std::make_shared<CascadeHashProjection>(
        meanDescriptor({descriptors1, descriptors2}), hashSeed(options));
  }
  return matchDescriptors(DescriptorIndex(descriptors1, options, projection),
                          DescriptorIndex(descriptors2, options, projection), options);
}

}  // namespace auv::recon::features
