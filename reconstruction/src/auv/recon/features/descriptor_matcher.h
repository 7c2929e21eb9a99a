#pragma once
// Putative matches between two images' descriptors (paper section 3.4.1): nearest neighbours by
// Euclidean distance (k = 2), Lowe's ratio test (D. Lowe, "Distinctive image features from
// scale-invariant keypoints", IJCV 2004, section 7.1) and a mutual (cross) check.

#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/flann.hpp>

#include "auv/recon/features/cascade_hash.h"
#include "auv/recon/features/match_store.h"

namespace auv::recon::features {

struct MatchingOptions {
  /// Lowe's ratio: keep a match when d(best) < ratio * d(second best).
  double ratio = 0.8;
  /// Keep only matches that are also the best match in the other direction.
  bool mutual = true;
  /// Images with more descriptors than this are searched approximately (`search`); smaller
  /// ones by brute force (exact).
  int flann_above = 4000;
  /// The approximate search: "cascade_hash" (cascade_hash.h; 5-10x faster at 8000
  /// descriptors) or "kdtree" (a FLANN forest of flann_trees trees, flann_checks checks).
  std::string search = "cascade_hash";
  /// cascade_hash: exact distances per query, for the candidates closest in Hamming distance.
  int hash_candidates = 10;
  /// The random draw of either search (the hashing's directions, the forest's trees): the
  /// same seed gives the same matches in every run and shard; another seed, another sample
  /// of the same approximation (bench/features: how much the SfM moves with it).
  int random_seed = 0;
  /// Randomised k-d trees of the forest.
  int flann_trees = 4;
  /// FLANN leaf checks (more: closer to exact, slower).
  int flann_checks = 64;

  void check() const;
};

/// The seed of the cascade hashing's directions for `options` (random_seed).
uint64_t hashSeed(const MatchingOptions& options);

/// One image's descriptors ready for nearest-neighbour queries: as CV_32F, hashed or with a
/// FLANN k-d forest above MatchingOptions::flann_above rows. Built once per image and shared
/// by every pair it is in, in both directions (building the forest costs as much as half a
/// pair's queries at 16k descriptors). Queries are const and may run from several threads.
class DescriptorIndex {
 public:
  /// `descriptors`: CV_8U or CV_32F rows. `projection`: the hashing every image of the
  /// collection shares (search "cascade_hash"; nullptr: one centred on these descriptors,
  /// for an index searched only by itself). Throws std::invalid_argument for other types.
  DescriptorIndex(const cv::Mat& descriptors, const MatchingOptions& options,
                  std::shared_ptr<const CascadeHashProjection> projection = nullptr);

  int rows() const { return descriptors_.rows; }
  int cols() const { return descriptors_.cols; }
  bool approximate() const { return approximate_; }
  /// The k (1 or 2, <= rows()) nearest rows of this index for rows `rows` of `queries` (an
  /// index of the same width and search): `indices` CV_32S and `distances` CV_32F
  /// (Euclidean), one row per query row; -1 where an approximate search found none.
  void knn(const DescriptorIndex& queries, const std::vector<int>& rows, int k, cv::Mat* indices,
           cv::Mat* distances) const;
  const cv::Mat& descriptors() const { return descriptors_; }

 private:
  cv::Mat descriptors_;                       // CV_32F
  bool approximate_ = false;                  // above flann_above rows
  std::shared_ptr<cv::flann::Index> forest_;  // "kdtree", approximate
  // "cascade_hash": every index is hashed, so that it can query an approximate one.
  std::shared_ptr<const CascadeHashProjection> projection_;
  std::shared_ptr<const HashedDescriptors> hashed_;
  int checks_ = 64;
  int hash_candidates_ = 10;
};

/// Matches of index1's rows to index2's rows. Returns (row in 1, row in 2) sorted by row in 1.
/// Throws std::invalid_argument for descriptors of different widths.
std::vector<MatchIndices> matchDescriptors(const DescriptorIndex& index1,
                                           const DescriptorIndex& index2,
                                           const MatchingOptions& options);

/// The same for two descriptor matrices (CV_8U or CV_32F, same width and type): builds both
/// indexes, hashed about the two images' mean (use the overload above, with one projection
/// for the collection, when an image takes part in several pairs).
std::vector<MatchIndices> matchDescriptors(const cv::Mat& descriptors1, const cv::Mat& descriptors2,
                                           const MatchingOptions& options);

}  // namespace auv::recon::features
