#pragma once
// Putative matches between two images' descriptors (paper section 3.4.1): nearest neighbours by
// Euclidean distance (k = 2), Lowe's ratio test (D. Lowe, "Distinctive image features from
// scale-invariant keypoints", IJCV 2004, section 7.1) and a mutual (cross) check.

#include <memory>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/flann.hpp>

#include "auv/recon/features/match_store.h"

namespace auv::recon::features {

struct MatchingOptions {
  /// Lowe's ratio: keep a match when d(best) < ratio * d(second best).
  double ratio = 0.8;
  /// Keep only matches that are also the best match in the other direction.
  bool mutual = true;
  /// Images with more descriptors than this are searched through a FLANN k-d forest
  /// (approximate); smaller ones by brute force (exact).
  int flann_above = 4000;
  /// Randomised k-d trees of the forest.
  int flann_trees = 4;
  /// FLANN leaf checks (more: closer to exact, slower).
  int flann_checks = 64;

  void check() const;
};

/// One image's descriptors ready for nearest-neighbour queries: as CV_32F, with a FLANN k-d
/// forest above MatchingOptions::flann_above rows. Built once per image and shared by every
/// pair it is in, in both directions (building the forest costs as much as half a pair's
/// queries at 16k descriptors). Queries are const and may run from several threads.
class DescriptorIndex {
 public:
  /// `descriptors`: CV_8U or CV_32F rows. Throws std::invalid_argument for other types.
  DescriptorIndex(const cv::Mat& descriptors, const MatchingOptions& options);

  int rows() const { return descriptors_.rows; }
  int cols() const { return descriptors_.cols; }
  bool approximate() const { return forest_ != nullptr; }
  /// The k (<= rows()) nearest rows of this index for each row of `queries` (CV_32F, same
  /// width): `indices` CV_32S and `distances` CV_32F (Euclidean), one row per query.
  void knn(const cv::Mat& queries, int k, cv::Mat* indices, cv::Mat* distances) const;
  const cv::Mat& descriptors() const { return descriptors_; }

 private:
  cv::Mat descriptors_;                       // CV_32F
  std::shared_ptr<cv::flann::Index> forest_;  // null: brute force
  int checks_ = 64;
};

/// Matches of index1's rows to index2's rows. Returns (row in 1, row in 2) sorted by row in 1.
/// Throws std::invalid_argument for descriptors of different widths.
std::vector<MatchIndices> matchDescriptors(const DescriptorIndex& index1,
                                           const DescriptorIndex& index2,
                                           const MatchingOptions& options);

/// The same for two descriptor matrices (CV_8U or CV_32F, same width and type): builds both
/// indexes (use the overload above when an image takes part in several pairs).
std::vector<MatchIndices> matchDescriptors(const cv::Mat& descriptors1, const cv::Mat& descriptors2,
                                           const MatchingOptions& options);

}  // namespace auv::recon::features
