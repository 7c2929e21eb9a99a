// Cascade hashing (cascade_hash.h) against an exact search on synthetic descriptors: the
// nearest neighbours it finds, its codes, and the errors it names.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "auv/recon/features/cascade_hash.h"

namespace auv::recon::features {
namespace {

/// SIFT-like rows: non-negative, 128 wide, uint8 range.
cv::Mat siftLike(int rows, std::mt19937_64& random) {
  std::gamma_distribution<float> magnitude(1.5f, 20.f);
  cv::Mat d(rows, 128, CV_32F);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < 128; ++c) d.at<float>(r, c) = std::min(255.f, magnitude(random));
  }
  return d;
}

/// `d` with Gaussian noise of `sigma` on every element.
cv::Mat perturbed(const cv::Mat& d, float sigma, std::mt19937_64& random) {
  std::normal_distribution<float> noise(0.f, sigma);
  cv::Mat out = d.clone();
  for (int r = 0; r < out.rows; ++r) {
    for (int c = 0; c < out.cols; ++c) out.at<float>(r, c) += noise(random);
  }
  return out;
}

TEST(CascadeHash, FindsTheExactNearestNeighbourOfMostQueriesWithItsExactDistance) {
  // 3000 reference rows; 1000 queries are noisy copies of references 0-999. The noise (sigma
  // 8 per element, ~90 in distance) is about a third of the distance between random rows,
  // like SIFT descriptors of one point in two views.
  std::mt19937_64 random(11);
  const cv::Mat references = siftLike(3000, random);
  const cv::Mat queries = perturbed(references.rowRange(0, 1000), 8.f, random);
  const CascadeHashProjection projection(meanDescriptor({references, queries}), 1);
  const HashedDescriptors hashed_references = projection.hash(references);
  const HashedDescriptors hashed_queries = projection.hash(queries);
  ASSERT_EQ(hashed_references.size(), 3000u);
  for (int g = 0; g < HashedDescriptors::kGroups; ++g) {
    EXPECT_EQ(hashed_references.start[g][HashedDescriptors::kBuckets], 3000);
  }

  std::vector<int> rows(1000);
  for (int i = 0; i < 1000; ++i) rows[i] = i;
  cv::Mat indices, distances;
  cascadeHashKnn(references, hashed_references, queries, hashed_queries, rows, 2, 10, &indices,
                 &distances);
  cv::Mat exact_distances, exact_indices;
  cv::batchDistance(queries, references, exact_distances, CV_32F, exact_indices, cv::NORM_L2, 2);
  int found = 0;
  for (int q = 0; q < 1000; ++q) {
    const int nearest = indices.at<int>(q, 0);
    if (nearest == exact_indices.at<int>(q, 0)) ++found;
    if (nearest >= 0) {
      // Distances are exact for the rows returned, and ordered.
      EXPECT_NEAR(distances.at<float>(q, 0), cv::norm(queries.row(q), references.row(nearest)),
                  1e-2);
      EXPECT_LE(distances.at<float>(q, 0), distances.at<float>(q, 1));
    }
  }
  EXPECT_GE(found, 950) << "of 1000 queries, the true nearest neighbour";
}

TEST(CascadeHash, CodesAreTheSameForTheSameSeedAndMean) {
  std::mt19937_64 random(12);
  const cv::Mat d = siftLike(200, random);
  const cv::Mat mean = meanDescriptor({d});
  const HashedDescriptors a = CascadeHashProjection(mean, 1).hash(d);
  const HashedDescriptors b = CascadeHashProjection(mean, 1).hash(d);
  const HashedDescriptors other_seed = CascadeHashProjection(mean, 7).hash(d);
  EXPECT_EQ(a.codes, b.codes);
  EXPECT_EQ(a.buckets, b.buckets);
  EXPECT_NE(a.codes, other_seed.codes);
  // Centred on the mean, each code bit splits the rows roughly in half.
  int ones = 0;
  for (const auto& code : a.codes) ones += __builtin_popcountll(code[0]);
  EXPECT_NEAR(ones / (200.0 * 64), 0.5, 0.1);
}

TEST(CascadeHash, QueriesWithoutCandidatesGetNoNeighbour) {
  // One reference row; a query on the far side of the mean shares none of its buckets.
  cv::Mat references = cv::Mat::zeros(2, 128, CV_32F);
  references.row(0).setTo(10.f);
  references.row(1).setTo(10.f);
  cv::Mat queries = cv::Mat::zeros(1, 128, CV_32F);
  queries.setTo(-10.f);
  const CascadeHashProjection projection(cv::Mat::zeros(1, 128, CV_32F), 1);
  cv::Mat indices, distances;
  cascadeHashKnn(references, projection.hash(references), queries, projection.hash(queries), {0}, 2,
                 10, &indices, &distances);
  EXPECT_EQ(indices.at<int>(0, 0), -1);
  EXPECT_TRUE(std::isinf(distances.at<float>(0, 0)));
}

TEST(CascadeHash, BadInputsAreNamed) {
  EXPECT_THROW(CascadeHashProjection(cv::Mat::zeros(2, 128, CV_32F), 1), std::invalid_argument);
  EXPECT_THROW(CascadeHashProjection(cv::Mat::zeros(1, 128, CV_64F), 1), std::invalid_argument);
  const CascadeHashProjection projection(cv::Mat::zeros(1, 128, CV_32F), 1);
  EXPECT_THROW(projection.hash(cv::Mat::zeros(3, 64, CV_32F)), std::invalid_argument);
  EXPECT_THROW(projection.hash(cv::Mat::zeros(3, 128, CV_8U)), std::invalid_argument);
  EXPECT_THROW(meanDescriptor({}), std::invalid_argument);
  EXPECT_THROW(meanDescriptor({cv::Mat::zeros(2, 128, CV_32F), cv::Mat::zeros(2, 64, CV_32F)}),
               std::invalid_argument);
  const cv::Mat d = cv::Mat::zeros(3, 128, CV_32F);
  const HashedDescriptors h = projection.hash(d);
  cv::Mat indices, distances;
  EXPECT_THROW(cascadeHashKnn(d, h, d, h, {0}, 3, 10, &indices, &distances), std::invalid_argument);
  EXPECT_THROW(cascadeHashKnn(d, h, d, h, {0}, 2, 1, &indices, &distances), std::invalid_argument);
}

}  // namespace
}  // namespace auv::recon::features
