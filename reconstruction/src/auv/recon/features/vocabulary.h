#pragma once
// Global image descriptors for loop-closure candidates: a bag of visual words (J. Sivic,
// A. Zisserman, "Video Google", ICCV 2003) trained on the survey's own descriptors with
// k-means (cv::kmeans), tf-idf weighted, L2-normalised; similarity = cosine.

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

namespace auv::recon::features {

class Vocabulary {
 public:
  /// Trains `words` centres on a sample of `descriptors` (CV_8U or CV_32F rows; at most
  /// `max_training` rows are used). Throws std::invalid_argument when there are fewer rows
  /// than words.
  static Vocabulary train(const cv::Mat& descriptors, int words, int max_training = 100000,
                          uint64_t seed = 42);

  int words() const { return centres_.rows; }
  /// Word histogram of one image (counts, 1 x words, CV_32F).
  cv::Mat histogram(const cv::Mat& descriptors) const;
  /// tf-idf weighted, L2-normalised global descriptors of all images' histograms (one row per
  /// image), and their n x n cosine similarity (CV_32F, diagonal 0).
  static cv::Mat tfIdf(const std::vector<cv::Mat>& histograms);
  static cv::Mat similarity(const cv::Mat& global_descriptors);

 private:
  cv::Mat centres_;  ///< words x 128, CV_32F
};

}  // namespace auv::recon::features
