#pragma once
// Cascade hashing of real-valued descriptors (J. Cheng, C. Leng, J. Wu, H. Cui, H. Lu, "Fast and
// accurate image matching with cascade hashing for 3D reconstruction", CVPR 2014). Descriptors
// centred on the collection's mean are projected on random directions:
//   1. 10 groups of 8 signs put each descriptor in one of 256 buckets per group; a query's
//      candidates are the rows sharing a bucket with it in any group (the paper's 6 groups
//      miss about one true match in seven: features/README.md);
//   2. 128 more signs make a binary code; candidates are ranked by Hamming distance;
//   3. only the best-ranked candidates get their exact Euclidean distance.
// An image is hashed once and searched in every pair it is in. Per query it costs a few
// hundred popcounts and ten distances where a k-d forest walks its trees (features/README.md).

#include <array>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

namespace auv::recon::features {

/// One image's descriptors hashed by a CascadeHashProjection.
struct HashedDescriptors {
  static constexpr int kGroups = 10;
  static constexpr int kBucketBits = 8;
  static constexpr int kBuckets = 1 << kBucketBits;
  static constexpr int kCodeWords = 2;  // 128-bit codes

  std::vector<std::array<uint64_t, kCodeWords>> codes;  ///< per row
  std::vector<std::array<uint8_t, kGroups>> buckets;    ///< per row: its bucket in each group
  /// Per group, rows by bucket: bucket b holds rows[g][start[g][b]] .. rows[g][start[g][b+1]-1].
  std::array<std::vector<int>, kGroups> rows;
  std::array<std::array<int, kBuckets + 1>, kGroups> start{};

  size_t size() const { return codes.size(); }
};

/// The random directions and the mean that every image of a collection is hashed with (codes
/// of two images compare only when both used the same projection).
class CascadeHashProjection {
 public:
  /// `mean`: 1 x width CV_32F, the mean descriptor of the collection (meanDescriptor);
  /// `seed`: of the random directions. Throws std::invalid_argument for another mean's shape.
  CascadeHashProjection(const cv::Mat& mean, uint64_t seed);

  int width() const { return mean_.cols; }
  /// `descriptors`: CV_32F rows of width(). Throws std::invalid_argument otherwise.
  HashedDescriptors hash(const cv::Mat& descriptors) const;

 private:
  cv::Mat mean_;        // 1 x width
  cv::Mat directions_;  // (kGroups * kBucketBits + 64 * kCodeWords) x width
};

/// The mean row of the union of `descriptors` (CV_32F or CV_8U, one width; empty ones skipped),
/// as 1 x width CV_32F. Throws std::invalid_argument when all are empty or widths differ.
cv::Mat meanDescriptor(const std::vector<cv::Mat>& descriptors);

/// For each of `query_rows` of `queries` (hashed as `query_hashes`), its k (1 or 2) nearest
/// rows of `index` (hashed as `index_hashes`) among the `candidates` closest in Hamming
/// distance: `indices` CV_32S and `distances` CV_32F (Euclidean), one row per query row, -1 and
/// +inf where fewer were found. All descriptors CV_32F of one width.
void cascadeHashKnn(const cv::Mat& index, const HashedDescriptors& index_hashes,
                    const cv::Mat& queries, const HashedDescriptors& query_hashes,
                    const std::vector<int>& query_rows, int k, int candidates, cv::Mat* indices,
                    cv::Mat* distances);

}  // namespace auv::recon::features
