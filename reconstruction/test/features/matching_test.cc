// Ratio + mutual matching on synthetic descriptors, pair selection on a synthetic similarity
// structure, the vocabulary's similarity.
#include <algorithm>
#include <iterator>
#include <random>
#include <set>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "auv/recon/common/stage_error.h"
#include "auv/recon/features/descriptor_matcher.h"
#include "auv/recon/features/pair_selection.h"
#include "auv/recon/features/vocabulary.h"

namespace auv::recon::features {
namespace {

cv::Mat randomDescriptors(int rows, std::mt19937_64& random) {
  std::uniform_real_distribution<float> unit(0.f, 100.f);
  cv::Mat d(rows, 128, CV_32F);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < 128; ++c) d.at<float>(r, c) = unit(random);
  }
  return d;
}

cv::Mat withNoise(const cv::Mat& d, float sigma, std::mt19937_64& random) {
  std::normal_distribution<float> noise(0.f, sigma);
  cv::Mat out = d.clone();
  for (int r = 0; r < out.rows; ++r) {
    for (int c = 0; c < out.cols; ++c) out.at<float>(r, c) += noise(random);
  }
  return out;
}

TEST(DescriptorMatcher, RatioAndMutualTestsOnSyntheticDescriptors) {
  std::mt19937_64 random(1);
  // Image 1: 200 descriptors. Image 2: rows 0-149 are noisy copies of image 1's rows 0-149 in
  // reverse order (true matches), rows 150-249 random distractors.
  const cv::Mat d1 = randomDescriptors(200, random);
  cv::Mat d2 = withNoise(d1.rowRange(0, 150), 3.f, random);
  cv::flip(d2, d2, 0);
  cv::vconcat(d2, randomDescriptors(100, random), d2);
  // Ambiguity: image 1's row 10 appears twice in image 2 (rows 139 and a copy appended).
  cv::vconcat(d2, withNoise(d1.row(10), 3.f, random), d2);

  MatchingOptions options;
  const std::vector<MatchIndices> matches = matchDescriptors(d1, d2, options);
  std::set<uint32_t> matched;
  for (const MatchIndices& m : matches) {
    ASSERT_LT(m.first, 150u) << "an unmatched descriptor of image 1 was matched";
    EXPECT_EQ(m.second, 149u - m.first) << "wrong partner for row " << m.first;
    matched.insert(m.first);
  }
  EXPECT_EQ(matched.count(10u), 0u) << "the ratio test must reject the ambiguous row 10";
  EXPECT_GE(matches.size(), 145u);
  // Sorted by image 1's row, each image 2 row at most once.
  std::set<uint32_t> seconds;
  for (size_t i = 0; i < matches.size(); ++i) {
    if (i > 0) {
      EXPECT_LT(matches[i - 1].first, matches[i].first);
    }
    EXPECT_TRUE(seconds.insert(matches[i].second).second);
  }
  // uint8 descriptors give the same answer.
  cv::Mat u1, u2;
  d1.convertTo(u1, CV_8U);
  d2.convertTo(u2, CV_8U);
  EXPECT_EQ(matchDescriptors(u1, u2, options).size(), matches.size());
}

TEST(DescriptorMatcher, MutualCheckRemovesOneSidedMatches) {
  // Two descriptors of image 1 (a, b) whose best match in image 2 is the same row c; only the
  // closer one (a) is c's best match back.
  cv::Mat d1 = cv::Mat::zeros(2, 128, CV_32F), d2 = cv::Mat::zeros(3, 128, CV_32F);
  d1.at<float>(0, 0) = 10.f;   // a
  d1.at<float>(1, 0) = 14.f;   // b
  d2.at<float>(0, 0) = 11.f;   // c, near both
  d2.at<float>(1, 1) = 200.f;  // far
  d2.at<float>(2, 2) = 200.f;  // far
  MatchingOptions options;
  options.mutual = false;
  EXPECT_EQ(matchDescriptors(d1, d2, options).size(), 2u);
  options.mutual = true;
  const auto mutual = matchDescriptors(d1, d2, options);
  ASSERT_EQ(mutual.size(), 1u);
  EXPECT_EQ(mutual[0], MatchIndices(0, 0));
}

TEST(DescriptorMatcher, BothApproximateSearchesAgreeWithBruteForce) {
  std::mt19937_64 random(2);
  const cv::Mat d1 = randomDescriptors(600, random);
  const cv::Mat d2 = withNoise(d1, 2.f, random);
  MatchingOptions exact;
  const auto a = matchDescriptors(d1, d2, exact);
  EXPECT_GE(a.size(), 590u);
  for (const std::string search : {"cascade_hash", "kdtree"}) {
    MatchingOptions approximate;
    approximate.flann_above = 100;
    approximate.search = search;
    const auto b = matchDescriptors(d1, d2, approximate);
    std::vector<MatchIndices> common;
    std::set_intersection(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(common));
    EXPECT_GE(common.size(), 0.95 * a.size()) << search;
    EXPECT_GE(common.size(), 0.99 * b.size()) << search << ": matches brute force does not make";
  }
}

TEST(DescriptorMatcher, OneIndexPerImageServesEveryPairFromSeveralThreads) {
  // Three images sharing 400 descriptors (noisy copies); each image's forest is built once and
  // queried by both directions of every pair it is in, from two threads at once: the answers
  // are those of matching each pair from scratch.
  std::mt19937_64 random(3);
  const cv::Mat base = randomDescriptors(400, random);
  const std::vector<cv::Mat> images = {withNoise(base, 2.f, random), withNoise(base, 2.f, random),
                                       withNoise(base, 2.f, random)};
  for (const std::string search : {"cascade_hash", "kdtree"}) {
    SCOPED_TRACE(search);
    MatchingOptions options;
    options.flann_above = 100;
    options.search = search;
    // One hashing for the collection (cascade_hash), as the match stage makes.
    const auto projection =
        std::make_shared<CascadeHashProjection>(meanDescriptor(images), hashSeed(options));
    std::vector<DescriptorIndex> indexes;
    for (const cv::Mat& d : images) indexes.emplace_back(d, options, projection);
    ASSERT_TRUE(indexes[0].approximate());
    EXPECT_FALSE(DescriptorIndex(base.rowRange(0, 50), options).approximate());

    const std::vector<std::pair<int, int>> pairs = {{0, 1}, {0, 2}, {1, 2}, {1, 0}};
    std::vector<std::vector<MatchIndices>> shared(pairs.size()), expected(pairs.size());
    for (size_t p = 0; p < pairs.size(); ++p) {
      expected[p] = matchDescriptors(images[pairs[p].first], images[pairs[p].second], options);
      EXPECT_GE(expected[p].size(), 380u) << p;
    }
    std::vector<std::thread> threads;
    for (int t = 0; t < 2; ++t) {
      threads.emplace_back([&, t] {
        for (size_t p = t; p < pairs.size(); p += 2) {
          shared[p] = matchDescriptors(indexes[pairs[p].first], indexes[pairs[p].second], options);
        }
      });
    }
    for (std::thread& t : threads) t.join();
    for (size_t p = 0; p < pairs.size(); ++p) {
      // FLANN's randomised trees differ between builds: the same matches up to a few misses.
      std::vector<MatchIndices> common;
      std::set_intersection(shared[p].begin(), shared[p].end(), expected[p].begin(),
                            expected[p].end(), std::back_inserter(common));
      EXPECT_GE(common.size(), 0.97 * expected[p].size()) << p;
      EXPECT_GE(common.size(), 0.97 * shared[p].size()) << p;
    }
  }
}

TEST(DescriptorMatcher, IndexesHashedDifferentlyAreNotCompared) {
  // Codes of two projections mean nothing to each other: refused, not silently wrong.
  std::mt19937_64 random(4);
  const cv::Mat d = randomDescriptors(300, random);
  MatchingOptions options;
  options.flann_above = 100;
  const DescriptorIndex own1(d, options), own2(d, options);
  EXPECT_THROW(matchDescriptors(own1, own2, options), std::invalid_argument);
}

TEST(DescriptorMatcher, BadInputs) {
  EXPECT_TRUE(matchDescriptors(cv::Mat(), cv::Mat::zeros(5, 128, CV_32F), {}).empty());
  EXPECT_THROW(matchDescriptors(cv::Mat::zeros(5, 128, CV_32F), cv::Mat::zeros(5, 64, CV_32F), {}),
               std::invalid_argument);
  MatchingOptions options;
  options.ratio = 1.5;
  EXPECT_THROW(DescriptorIndex(cv::Mat::zeros(5, 128, CV_64F), {}), std::invalid_argument);
  try {
    options.check();
    FAIL() << "no exception";
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("ratio = 1.5"), std::string::npos);
  }
  MatchingOptions unknown_search;
  unknown_search.search = "lsh";
  try {
    unknown_search.check();
    FAIL() << "no exception";
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("search = lsh: must be cascade_hash or kdtree"),
              std::string::npos);
  }
}

std::set<std::pair<int, int>> pairSet(const std::vector<CandidatePair>& pairs, PairSource source) {
  std::set<std::pair<int, int>> out;
  for (const CandidatePair& p : pairs) {
    if (p.source == source) out.insert({p.index1, p.index2});
  }
  return out;
}

TEST(PairSelection, ExhaustiveForSmallSets) {
  std::vector<PairImage> images(10);
  for (int i = 0; i < 10; ++i) images[i] = {"cam/" + std::to_string(i) + ".png", "cam", i};
  const auto pairs = selectPairs(images, cv::Mat(), PairSelectionOptions{});
  EXPECT_EQ(pairs.size(), 45u);
  EXPECT_EQ(pairSet(pairs, PairSource::EXHAUSTIVE).size(), 45u);
}

TEST(PairSelection, SequentialLoopAndCrossCameraPairsOnASyntheticStructure) {
  // Camera "left": 80 keyframes along a lawnmower track whose last 10 revisit the first 10
  // (image 70 + k sees what image k saw). Camera "right": 20 keyframes synchronised with left's
  // first 20 by sim time, and visually similar to them.
  const int n_left = 80, n_right = 20;
  std::vector<PairImage> images;
  for (int i = 0; i < n_left; ++i) {
    images.push_back({"left/" + std::to_string(i) + ".png", "left", i, 1.0 * i});
  }
  for (int i = 0; i < n_right; ++i) {
    images.push_back({"right/" + std::to_string(i) + ".png", "right", i, 1.0 * i + 0.3});
  }
  const int n = static_cast<int>(images.size());
  cv::Mat similarity = cv::Mat::zeros(n, n, CV_32F);
  auto set = [&](int a, int b, float s) {
    similarity.at<float>(a, b) = s;
    similarity.at<float>(b, a) = s;
  };
  for (int a = 0; a < n_left; ++a) {
    for (int b = 0; b < n_left; ++b) {
      if (a != b) set(a, b, 0.02f + 0.5f / (1 + std::abs(a - b)));  // neighbours alike
    }
  }
  for (int k = 0; k < 10; ++k) set(k, 70 + k, 0.9f);  // the revisit
  for (int k = 0; k < n_right; ++k) set(k, n_left + k, 0.8f);

  PairSelectionOptions options;
  options.sequential_window = 3;
  options.loop_top_k = 2;
  options.loop_min_separation = 10;
  options.cross_camera_max_dt_s = 0.5;
  const auto pairs = selectPairs(images, similarity, options);

  const auto sequential = pairSet(pairs, PairSource::SEQUENTIAL);
  for (int i = 0; i + 3 < n_left; ++i) {
    for (int d = 1; d <= 3; ++d) EXPECT_TRUE(sequential.count({i, i + d})) << i << "," << i + d;
  }
  EXPECT_FALSE(sequential.count({0, 4}));
  EXPECT_TRUE(sequential.count({n_left, n_left + 1}));
  EXPECT_FALSE(sequential.count({n_left - 1, n_left}));  // different cameras
  // (n_left - 1)*3 - 3 left pairs + 19*3 - 3 right pairs.
  EXPECT_EQ(sequential.size(), static_cast<size_t>((n_left - 3) * 3 + 3 + (n_right - 3) * 3 + 3));

  const auto loops = pairSet(pairs, PairSource::LOOP);
  for (int k = 0; k < 10; ++k) EXPECT_TRUE(loops.count({k, 70 + k})) << k;
  for (const auto& [a, b] : loops) {
    EXPECT_GE(b - a, 10) << "loop candidate closer than loop_min_separation: " << a << "," << b;
  }
  const auto cross = pairSet(pairs, PairSource::CROSS_CAMERA);
  for (int k = 0; k < n_right; ++k) EXPECT_TRUE(cross.count({k, n_left + k})) << k;
  EXPECT_FALSE(cross.count({0, n_left + 5}));  // 5.3 s apart, not alike
  // Each pair once, sorted.
  for (size_t i = 1; i < pairs.size(); ++i) {
    EXPECT_LT(std::make_pair(pairs[i - 1].index1, pairs[i - 1].index2),
              std::make_pair(pairs[i].index1, pairs[i].index2));
  }
}

TEST(PairSelection, NavigationKeepsLookAlikesFarApartOutOfTheLoopCandidates) {
  // 60 keyframes of one camera along a straight 59 m track (1 m apart). Keyframe 40 + k looks
  // just like keyframe k (a repeated texture 40 m further on), and keyframe 55 revisits the
  // place of keyframe 5 (the track turns back: both at x = 5 m).
  const int n = 60;
  std::vector<PairImage> images;
  for (int i = 0; i < n; ++i) {
    PairImage image{"c/" + std::to_string(i) + ".png", "c", i, 1.0 * i};
    image.has_position = true;
    image.position = Eigen::Vector3d(i, 0, 3);
    images.push_back(image);
  }
  images[55].position = Eigen::Vector3d(5, 1, 3);
  cv::Mat similarity = cv::Mat::zeros(n, n, CV_32F);
  auto set = [&](int a, int b, float s) {
    similarity.at<float>(a, b) = s;
    similarity.at<float>(b, a) = s;
  };
  for (int k = 0; k < 20; ++k) set(k, 40 + k, 0.9f);  // look-alikes 40 m apart
  set(5, 55, 0.8f);                                   // the true revisit
  PairSelectionOptions options;
  options.sequential_window = 2;
  options.loop_top_k = 2;
  options.cross_camera_max_dt_s = 0;

  // Without navigation (images without positions) the look-alikes are candidates.
  std::vector<PairImage> blind = images;
  for (PairImage& image : blind) image.has_position = false;
  const auto blind_loops = pairSet(selectPairs(blind, similarity, options), PairSource::LOOP);
  for (int k = 0; k < 20; ++k) EXPECT_TRUE(blind_loops.count({k, 40 + k})) << k;

  // With it, only candidates within loop_max_distance_m (10 m) remain: the revisit.
  const auto loops = pairSet(selectPairs(images, similarity, options), PairSource::LOOP);
  EXPECT_TRUE(loops.count({5, 55}));
  for (const auto& [a, b] : loops) {
    EXPECT_LE((images[a].position - images[b].position).norm(), 10.0) << a << "," << b;
  }
  // 0: no limit.
  options.loop_max_distance_m = 0;
  const auto unlimited = pairSet(selectPairs(images, similarity, options), PairSource::LOOP);
  EXPECT_TRUE(unlimited.count({0, 40}));
}

TEST(PairSelection, BadSimilaritySizeAndOptions) {
  std::vector<PairImage> images(60);
  for (int i = 0; i < 60; ++i) images[i] = {"c/" + std::to_string(i), "c", i};
  EXPECT_THROW(selectPairs(images, cv::Mat::zeros(5, 5, CV_32F), {}), std::invalid_argument);
  PairSelectionOptions options;
  options.sequential_window = -1;
  EXPECT_THROW(options.check(), OptionError);
  options.sequential_window = 6;
  options.loop_max_distance_m = -1;
  EXPECT_THROW(options.check(), OptionError);
}

TEST(Vocabulary, SimilarImagesScoreHigherThanDifferentOnes) {
  // Two "places", each with its own 40 visual patterns; images of one place draw noisy copies
  // of that place's patterns.
  std::mt19937_64 random(3);
  const cv::Mat place_a = randomDescriptors(40, random), place_b = randomDescriptors(40, random);
  std::uniform_int_distribution<int> pick(0, 39);
  std::vector<cv::Mat> images;
  for (int i = 0; i < 6; ++i) {
    const cv::Mat& place = i < 3 ? place_a : place_b;
    cv::Mat d;
    for (int k = 0; k < 150; ++k) d.push_back(withNoise(place.row(pick(random)), 2.f, random));
    images.push_back(d);
  }
  cv::Mat all;
  for (const cv::Mat& d : images) all.push_back(d);
  const Vocabulary vocabulary = Vocabulary::train(all, 64);
  EXPECT_EQ(vocabulary.words(), 64);
  std::vector<cv::Mat> histograms;
  for (const cv::Mat& d : images) histograms.push_back(vocabulary.histogram(d));
  EXPECT_EQ(cv::sum(histograms[0])[0], 150.0);
  const cv::Mat s = Vocabulary::similarity(Vocabulary::tfIdf(histograms));
  for (int a = 0; a < 6; ++a) {
    EXPECT_EQ(s.at<float>(a, a), 0.f);
    for (int b = 0; b < 6; ++b) {
      if (a == b) continue;
      const bool same = (a < 3) == (b < 3);
      if (same) {
        EXPECT_GT(s.at<float>(a, b), 0.5f) << a << "," << b;
      } else {
        EXPECT_LT(s.at<float>(a, b), 0.1f) << a << "," << b;
      }
    }
  }
  EXPECT_THROW(Vocabulary::train(images[0].rowRange(0, 10), 64), std::invalid_argument);
}

}  // namespace
}  // namespace auv::recon::features
