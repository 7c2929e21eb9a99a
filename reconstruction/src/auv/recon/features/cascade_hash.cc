#include "auv/recon/features/cascade_hash.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <opencv2/core/hal/hal.hpp>

namespace auv::recon::features {
namespace {

constexpr int kGroups = HashedDescriptors::kGroups;
constexpr int kBucketBits = HashedDescriptors::kBucketBits;
constexpr int kBuckets = HashedDescriptors::kBuckets;
constexpr int kCodeBits = 64 * HashedDescriptors::kCodeWords;
constexpr int kDirections = kGroups * kBucketBits + kCodeBits;

int hamming(const std::array<uint64_t, 2>& a, const std::array<uint64_t, 2>& b) {
  return __builtin_popcountll(a[0] ^ b[0]) + __builtin_popcountll(a[1] ^ b[1]);
}

}  // namespace

CascadeHashProjection::CascadeHashProjection(const cv::Mat& mean, uint64_t seed) {
  if (mean.rows != 1 || mean.cols < 1 || mean.type() != CV_32F) {
    throw std::invalid_argument("CascadeHashProjection: the mean must be one CV_32F row");
  }
  mean_ = mean.clone();
  directions_.create(kDirections, mean.cols, CV_32F);
  cv::RNG rng(seed);
  rng.fill(directions_, cv::RNG::NORMAL, 0.0, 1.0);
}

HashedDescriptors CascadeHashProjection::hash(const cv::Mat& descriptors) const {
  if (!descriptors.empty() && (descriptors.type() != CV_32F || descriptors.cols != width())) {
    throw std::invalid_argument("CascadeHashProjection: descriptors must be CV_32F rows of " +
                                std::to_string(width()) + " columns");
  }
  HashedDescriptors hashed;
  const int n = descriptors.rows;
  hashed.codes.assign(n, {0, 0});
  hashed.buckets.assign(n, {});
  if (n == 0) return hashed;
  cv::Mat centred = descriptors - cv::repeat(mean_, n, 1);
  cv::Mat projected;  // n x kDirections
  cv::gemm(centred, directions_, 1.0, cv::noArray(), 0.0, projected, cv::GEMM_2_T);
  for (int row = 0; row < n; ++row) {
    const float* p = projected.ptr<float>(row);
    for (int g = 0; g < kGroups; ++g) {
      uint8_t bucket = 0;
      for (int bit = 0; bit < kBucketBits; ++bit) {
        bucket = static_cast<uint8_t>((bucket << 1) | (p[g * kBucketBits + bit] > 0 ? 1 : 0));
      }
      hashed.buckets[row][g] = bucket;
    }
    const float* code = p + kGroups * kBucketBits;
    for (int bit = 0; bit < kCodeBits; ++bit) {
      if (code[bit] > 0) hashed.codes[row][bit / 64] |= uint64_t{1} << (bit % 64);
    }
  }
  // Counting sort of the rows into each group's buckets.
  for (int g = 0; g < kGroups; ++g) {
    std::array<int, kBuckets + 1>& start = hashed.start[g];
    start.fill(0);
    for (int row = 0; row < n; ++row) ++start[hashed.buckets[row][g] + 1];
    for (int b = 0; b < kBuckets; ++b) start[b + 1] += start[b];
    std::vector<int> next(start.begin(), start.end() - 1);
    hashed.rows[g].resize(n);
    for (int row = 0; row < n; ++row) hashed.rows[g][next[hashed.buckets[row][g]]++] = row;
  }
  return hashed;
}

cv::Mat meanDescriptor(const std::vector<cv::Mat>& descriptors) {
  cv::Mat sum;
  double rows = 0;
  for (const cv::Mat& d : descriptors) {
    if (d.empty()) continue;
    cv::Mat row_sum;
    cv::reduce(d, row_sum, 0, cv::REDUCE_SUM, CV_64F);
    if (sum.empty()) {
      sum = row_sum;
    } else if (row_sum.cols != sum.cols) {
      throw std::invalid_argument("meanDescriptor: descriptors of " + std::to_string(sum.cols) +
                                  " and " + std::to_string(row_sum.cols) + " columns");
    } else {
      sum += row_sum;
    }
    rows += d.rows;
  }
  if (sum.empty()) throw std::invalid_argument("meanDescriptor: no descriptors");
  cv::Mat mean;
  sum.convertTo(mean, CV_32F, 1.0 / rows);
  return mean;
}

void cascadeHashKnn(const cv::Mat& index, const HashedDescriptors& index_hashes,
                    const cv::Mat& queries, const HashedDescriptors& query_hashes,
                    const std::vector<int>& query_rows, int k, int candidates, cv::Mat* indices,
                    cv::Mat* distances) {
  if (k < 1 || k > 2 || candidates < k) {
    throw std::invalid_argument("cascadeHashKnn: k must be 1 or 2 and candidates >= k");
  }
  if (index_hashes.size() != static_cast<size_t>(index.rows) ||
      query_hashes.size() != static_cast<size_t>(queries.rows) || index.cols != queries.cols) {
    throw std::invalid_argument("cascadeHashKnn: descriptors and their hashes disagree");
  }
  for (int row : query_rows) {
    if (row < 0 || row >= queries.rows) {
      throw std::out_of_range("cascadeHashKnn: query row " + std::to_string(row) + " of " +
                              std::to_string(queries.rows));
    }
  }
  const int n = static_cast<int>(query_rows.size());
  indices->create(n, k, CV_32S);
  distances->create(n, k, CV_32F);
  indices->setTo(-1);
  distances->setTo(std::numeric_limits<float>::infinity());
  // Per query: its candidates binned by Hamming distance (0..128), each index row once.
  std::vector<int> seen(index.rows, -1);
  std::array<std::vector<int>, kCodeBits + 1> by_distance;
  for (int q = 0; q < n; ++q) {
    const int row = query_rows[q];
    const auto& code = query_hashes.codes[row];
    int nearest_bin = kCodeBits + 1, farthest_bin = -1;
    for (int g = 0; g < kGroups; ++g) {
      const int bucket = query_hashes.buckets[row][g];
      const auto& rows = index_hashes.rows[g];
      for (int i = index_hashes.start[g][bucket]; i < index_hashes.start[g][bucket + 1]; ++i) {
        const int candidate = rows[i];
        if (seen[candidate] == q) continue;
        seen[candidate] = q;
        const int d = hamming(code, index_hashes.codes[candidate]);
        by_distance[d].push_back(candidate);
        nearest_bin = std::min(nearest_bin, d);
        farthest_bin = std::max(farthest_bin, d);
      }
    }
    // Exact distances for the `candidates` closest codes (all of the last bin reached, so the
    // outcome does not depend on the order rows were binned in).
    float best[2] = {std::numeric_limits<float>::infinity(),
                     std::numeric_limits<float>::infinity()};
    int best_row[2] = {-1, -1};
    const float* query = queries.ptr<float>(row);
    int measured = 0;
    for (int bin = nearest_bin; bin <= farthest_bin; ++bin) {
      if (measured >= candidates) {
        by_distance[bin].clear();
        continue;
      }
      for (int candidate : by_distance[bin]) {
        const float d2 = cv::hal::normL2Sqr_(query, index.ptr<float>(candidate), index.cols);
        if (d2 < best[0] || (d2 == best[0] && candidate < best_row[0])) {
          best[1] = best[0], best_row[1] = best_row[0];
          best[0] = d2, best_row[0] = candidate;
        } else if (d2 < best[1] || (d2 == best[1] && candidate < best_row[1])) {
          best[1] = d2, best_row[1] = candidate;
        }
      }
      measured += static_cast<int>(by_distance[bin].size());
      by_distance[bin].clear();
    }
    for (int j = 0; j < k; ++j) {
      indices->at<int>(q, j) = best_row[j];
      distances->at<float>(q, j) = std::sqrt(best[j]);
    }
  }
}

}  // namespace auv::recon::features
