#pragma once
// Putative matches between two images' descriptors (paper section 3.4.1): nearest neighbours by
// Euclidean distance (k = 2), Lowe's ratio test (D. Lowe, "Distinctive image features from
// scale-invariant keypoints", IJCV 2004, section 7.1) and a mutual (cross) check.

#include <vector>

#include <opencv2/core.hpp>

#include "auv/recon/features/match_store.h"

namespace auv::recon::features {

struct MatchingOptions {
  /// Lowe's ratio: keep a match when d(best) < ratio * d(second best).
  double ratio = 0.8;
  /// Keep only matches that are also the best match in the other direction.
  bool mutual = true;
  /// Above this many descriptors in both images, FLANN k-d trees (approximate) replace the
  /// brute-force matcher (exact).
  int flann_above = 4000;
  /// FLANN leaf checks (more: closer to exact, slower).
  int flann_checks = 64;

  void check() const;
};

/// Matches of descriptors1 (rows) to descriptors2 (rows), CV_8U or CV_32F, same width. Returns
/// (row in 1, row in 2) sorted by row in 1. Throws std::invalid_argument for descriptor
/// matrices of different types/widths.
std::vector<MatchIndices> matchDescriptors(const cv::Mat& descriptors1, const cv::Mat& descriptors2,
                                           const MatchingOptions& options);

}  // namespace auv::recon::features
