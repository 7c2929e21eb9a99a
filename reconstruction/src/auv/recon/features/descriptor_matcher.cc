#include "auv/recon/features/descriptor_matcher.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include <opencv2/features2d.hpp>
#include <opencv2/flann.hpp>

#include "auv/recon/common/stage_error.h"

namespace auv::recon::features {
namespace {

cv::Mat asFloat(const cv::Mat& descriptors) {
  if (descriptors.type() == CV_32F) return descriptors;
  cv::Mat out;
  descriptors.convertTo(out, CV_32F);
  return out;
}

cv::Ptr<cv::DescriptorMatcher> makeMatcher(bool approximate, int checks) {
  if (approximate) {
    return cv::makePtr<cv::FlannBasedMatcher>(cv::makePtr<cv::flann::KDTreeIndexParams>(4),
                                              cv::makePtr<cv::flann::SearchParams>(checks));
  }
  return cv::BFMatcher::create(cv::NORM_L2);
}

}  // namespace

void MatchingOptions::check() const {
  AUV_RECON_CHECK_OPTION(ratio > 0 && ratio <= 1, ratio, "must be in (0, 1]");
  AUV_RECON_CHECK_OPTION(flann_above >= 0, flann_above, "must be >= 0");
  AUV_RECON_CHECK_OPTION(flann_checks > 0, flann_checks, "must be > 0");
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
  if (descriptors2.rows < 2) return {};  // no second neighbour: the ratio test cannot pass
  const cv::Mat d1 = asFloat(descriptors1), d2 = asFloat(descriptors2);
  const bool approximate = std::min(d1.rows, d2.rows) > options.flann_above;

  std::vector<std::vector<cv::DMatch>> forward;
  makeMatcher(approximate, options.flann_checks)->knnMatch(d1, d2, forward, 2);
  std::vector<MatchIndices> matches;
  for (const auto& m : forward) {
    if (m.size() < 2) continue;
    // Lowe's test on distances (not squared): d1 < ratio * d2.
    if (!(m[0].distance < options.ratio * m[1].distance)) continue;
    matches.emplace_back(static_cast<uint32_t>(m[0].queryIdx),
                         static_cast<uint32_t>(m[0].trainIdx));
  }
  if (options.mutual && !matches.empty()) {
    // Best match back into image 1, only for the rows of image 2 that were matched (the same
    // answer as matching all of image 2 back, at a fraction of the cost).
    std::vector<int> rows2;
    for (const MatchIndices& m : matches) rows2.push_back(static_cast<int>(m.second));
    std::sort(rows2.begin(), rows2.end());
    rows2.erase(std::unique(rows2.begin(), rows2.end()), rows2.end());
    cv::Mat queries(static_cast<int>(rows2.size()), d2.cols, CV_32F);
    for (size_t i = 0; i < rows2.size(); ++i)
      d2.row(rows2[i]).copyTo(queries.row(static_cast<int>(i)));
    std::vector<std::vector<cv::DMatch>> backward;
    makeMatcher(approximate, options.flann_checks)->knnMatch(queries, d1, backward, 1);
    std::vector<int> best_back(d2.rows, -1);
    for (const auto& m : backward) {
      if (!m.empty()) best_back[rows2[m[0].queryIdx]] = m[0].trainIdx;
    }
    matches.erase(std::remove_if(matches.begin(), matches.end(),
                                 [&](const MatchIndices& m) {
                                   return best_back[m.second] != static_cast<int>(m.first);
                                 }),
                  matches.end());
  }
  std::sort(matches.begin(), matches.end());
  return matches;
}

}  // namespace auv::recon::features
