#pragma once
// SIFT extraction (paper section 3.4.1: SIFT keypoints and descriptors, here OpenCV's CPU
// cv::SIFT instead of SiftGPU) over the survey's corrected images, with RootSIFT descriptors
// (Arandjelovic & Zisserman, "Three things everyone should know to improve object retrieval",
// CVPR 2012: L1-normalise, square root; Euclidean distance then compares like the Hellinger
// kernel, which matches better than raw SIFT).

#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "auv/recon/common/survey.h"
#include "auv/recon/features/feature_store.h"

namespace auv::recon {
class OptionSet;
}

namespace auv::recon::features {

struct SiftOptions {
  /// Most keypoints kept per image (which ones: `keep`); 0: all.
  int max_features = 8000;
  /// Which keypoints max_features keeps: "largest" (coarsest scales first, as COLMAP does) or
  /// "strongest" (highest DoG response first, OpenCV's nfeatures). The strongest responses
  /// are mostly the finest scales, which are the least repeatable across viewpoint and scale
  /// changes.
  std::string keep = "largest";
  /// max_features holds for images up to this many megapixels (of the detection image); larger
  /// ones keep proportionally more (0: a fixed cap). The strongest responses of a 6 MP photo are
  /// mostly its finest scales, which match badly across viewpoints: Sceaux castle at 2832x2128
  /// kept 8000 and one photo found < 30 inliers with every other (10/11 registered); with
  /// 16000 all 11 registered.
  double max_features_megapixels = 3.0;
  /// DoG contrast threshold (cv::SIFT contrastThreshold, divided by the octave layers inside
  /// OpenCV). OpenCV's 0.04 finds too few keypoints on low-contrast underwater frames.
  double contrast_threshold = 0.02;
  /// Edge response threshold (ratio of principal curvatures).
  double edge_threshold = 10.0;
  /// Gaussian sigma of the first octave, px.
  double sigma = 1.6;
  /// Scales per octave.
  int octave_layers = 3;
  /// Images whose larger side exceeds this are downscaled for the detection, px (0: never);
  /// keypoints are returned in full-resolution pixels.
  int max_image_size = 3200;
  /// RootSIFT descriptors (else plain SIFT, L2-normalised); both stored as uint8 x 512.
  bool root_sift = true;

  void check() const;
};

/// SIFT of one image (BGR or grey, 8 bit). `image_name` goes into the result. Keypoints capped
/// at max_features (scaled by max_features_megapixels; chosen by `keep`), sorted by decreasing
/// response. `mask` (optional, CV_8U of the image's size, masks/mask.h): no keypoint where it
/// is 0.
ImageFeatures extractSift(const cv::Mat& image, const std::string& image_name,
                          const SiftOptions& options, const cv::Mat& mask = cv::Mat());

}  // namespace auv::recon::features
