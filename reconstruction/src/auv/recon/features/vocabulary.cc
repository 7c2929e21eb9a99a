#include "auv/recon/features/vocabulary.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

namespace auv::recon::features {

Vocabulary Vocabulary::train(const cv::Mat& descriptors, int words, int max_training,
                             uint64_t seed) {
  if (words < 2 || descriptors.rows < words) {
    throw std::invalid_argument("vocabulary: " + std::to_string(descriptors.rows) +
                                " descriptors cannot train " + std::to_string(words) + " words");
  }
  cv::Mat data;
  descriptors.convertTo(data, CV_32F);
  if (data.rows > max_training) {
    std::vector<int> rows(data.rows);
    std::iota(rows.begin(), rows.end(), 0);
    std::mt19937_64 random(seed);
    std::shuffle(rows.begin(), rows.end(), random);
    cv::Mat sample(max_training, data.cols, CV_32F);
    for (int i = 0; i < max_training; ++i) data.row(rows[i]).copyTo(sample.row(i));
    data = sample;
  }
  cv::setRNGSeed(static_cast<int>(seed));
  cv::Mat labels;
  Vocabulary vocabulary;
  cv::kmeans(data, words, labels,
             cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 8, 1e-3), 1,
             cv::KMEANS_PP_CENTERS, vocabulary.centres_);
  return vocabulary;
}

cv::Mat Vocabulary::histogram(const cv::Mat& descriptors) const {
  cv::Mat histogram = cv::Mat::zeros(1, words(), CV_32F);
  if (descriptors.empty()) return histogram;
  cv::Mat data;
  descriptors.convertTo(data, CV_32F);
  std::vector<cv::DMatch> nearest;
  cv::BFMatcher(cv::NORM_L2).match(data, centres_, nearest);
  for (const cv::DMatch& m : nearest) histogram.at<float>(0, m.trainIdx) += 1.0f;
  return histogram;
}

cv::Mat Vocabulary::tfIdf(const std::vector<cv::Mat>& histograms) {
  if (histograms.empty()) return {};
  const int n = static_cast<int>(histograms.size());
  const int words = histograms.front().cols;
  std::vector<int> document_frequency(words, 0);
  for (const cv::Mat& h : histograms) {
    for (int w = 0; w < words; ++w) document_frequency[w] += h.at<float>(0, w) > 0 ? 1 : 0;
  }
  cv::Mat global(n, words, CV_32F);
  for (int i = 0; i < n; ++i) {
    const cv::Mat& h = histograms[i];
    const double total = std::max(1.0, cv::sum(h)[0]);
    for (int w = 0; w < words; ++w) {
      const double idf = document_frequency[w] > 0
                             ? std::log(static_cast<double>(n) / document_frequency[w])
                             : 0.0;
      global.at<float>(i, w) = static_cast<float>(h.at<float>(0, w) / total * idf);
    }
    const double norm = cv::norm(global.row(i));
    if (norm > 0) global.row(i) /= norm;
  }
  return global;
}

cv::Mat Vocabulary::similarity(const cv::Mat& global_descriptors) {
  cv::Mat similarity = global_descriptors * global_descriptors.t();
  for (int i = 0; i < similarity.rows; ++i) similarity.at<float>(i, i) = 0.0f;
  return similarity;
}

}  // namespace auv::recon::features
