#include "auv/recon/features/sift_extractor.h"

#include <algorithm>
#include <cmath>

#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "auv/recon/common/stage_error.h"

namespace auv::recon::features {
namespace {

// Float SIFT rows (OpenCV: L2-normalised x 512) -> uint8 rows of (Root)SIFT x 512.
cv::Mat quantizeDescriptors(const cv::Mat& descriptors, bool root_sift) {
  cv::Mat out(descriptors.rows, descriptors.cols, CV_8U);
  for (int r = 0; r < descriptors.rows; ++r) {
    const float* in = descriptors.ptr<float>(r);
    uint8_t* o = out.ptr<uint8_t>(r);
    double norm = 0;
    for (int c = 0; c < descriptors.cols; ++c) {
      norm += root_sift ? std::abs(in[c]) : static_cast<double>(in[c]) * in[c];
    }
    norm = root_sift ? norm : std::sqrt(norm);
    if (!(norm > 0)) norm = 1;
    for (int c = 0; c < descriptors.cols; ++c) {
      const double v = root_sift ? std::sqrt(std::abs(in[c]) / norm) : in[c] / norm;
      o[c] = static_cast<uint8_t>(std::min(255.0, std::round(512.0 * v)));
    }
  }
  return out;
}

}  // namespace

void SiftOptions::check() const {
  AUV_RECON_CHECK_OPTION(max_features >= 0, max_features, "must be >= 0 (0: all)");
  AUV_RECON_CHECK_OPTION(keep == "largest" || keep == "strongest", keep,
                         "must be 'largest' or 'strongest'");
  AUV_RECON_CHECK_OPTION(max_features_megapixels >= 0, max_features_megapixels,
                         "must be >= 0 MP (0: a fixed cap)");
  AUV_RECON_CHECK_OPTION(contrast_threshold > 0 && contrast_threshold < 1, contrast_threshold,
                         "must be in (0, 1)");
  AUV_RECON_CHECK_OPTION(edge_threshold > 1, edge_threshold, "must be > 1");
  AUV_RECON_CHECK_OPTION(sigma > 0, sigma, "must be > 0 px");
  AUV_RECON_CHECK_OPTION(octave_layers >= 1 && octave_layers <= 10, octave_layers,
                         "must be in [1, 10]");
  AUV_RECON_CHECK_OPTION(max_image_size == 0 || max_image_size >= 64, max_image_size,
                         "must be 0 (never downscale) or >= 64 px");
}

ImageFeatures extractSift(const cv::Mat& image, const std::string& image_name,
                          const SiftOptions& options, const cv::Mat& mask) {
  options.check();
  if (image.empty() || image.depth() != CV_8U ||
      (image.channels() != 1 && image.channels() != 3 && image.channels() != 4)) {
    throw std::invalid_argument(image_name + ": not an 8-bit grey or colour image");
  }
  if (!mask.empty() && (mask.type() != CV_8UC1 || mask.size() != image.size())) {
    throw std::invalid_argument(image_name + ": the mask is not 8-bit grey of the image's size");
  }
  cv::Mat gray;
  if (image.channels() == 1) {
    gray = image;
  } else {
    cv::cvtColor(image, gray, image.channels() == 3 ? cv::COLOR_BGR2GRAY : cv::COLOR_BGRA2GRAY);
  }
  // Detect on a downscaled copy of very large images; map back to full-resolution pixels.
  double scale = 1.0;
  const int larger = std::max(gray.cols, gray.rows);
  if (options.max_image_size > 0 && larger > options.max_image_size) {
    scale = static_cast<double>(larger) / options.max_image_size;
    cv::Mat small;
    cv::resize(gray, small,
               cv::Size(static_cast<int>(std::lround(gray.cols / scale)),
                        static_cast<int>(std::lround(gray.rows / scale))),
               0, 0, cv::INTER_AREA);
    scale = static_cast<double>(gray.cols) / small.cols;
    gray = small;
  }
  int max_features = options.max_features;
  const double megapixels = static_cast<double>(gray.cols) * gray.rows / 1e6;
  if (max_features > 0 && options.max_features_megapixels > 0 &&
      megapixels > options.max_features_megapixels) {
    max_features =
        static_cast<int>(std::lround(max_features * megapixels / options.max_features_megapixels));
  }
  const bool strongest = options.keep == "strongest";
  // OpenCV's nfeatures keeps the strongest, and caps before it applies a mask: for the largest,
  // or with a mask (masked keypoints must not take the places of kept ones), detect all and
  // cap below.
  const cv::Ptr<cv::SIFT> sift =
      cv::SIFT::create(strongest && mask.empty() ? max_features : 0, options.octave_layers,
                       options.contrast_threshold, options.edge_threshold, options.sigma);
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  cv::Mat detection_mask = mask;  // at the detection scale; OpenCV drops keypoints where 0
  if (!mask.empty() && mask.size() != gray.size()) {
    cv::resize(mask, detection_mask, gray.size(), 0, 0, cv::INTER_NEAREST);
  }
  sift->detectAndCompute(gray, detection_mask, keypoints, descriptors);

  std::vector<int> order(keypoints.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  auto byResponse = [&](int a, int b) { return keypoints[a].response > keypoints[b].response; };
  if (!strongest) {
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
      return keypoints[a].size != keypoints[b].size ? keypoints[a].size > keypoints[b].size
                                                    : byResponse(a, b);
    });
  } else {
    std::stable_sort(order.begin(), order.end(), byResponse);
  }
  // Capped (OpenCV may keep ties beyond nfeatures), then strongest first.
  if (max_features > 0 && order.size() > static_cast<size_t>(max_features)) {
    order.resize(max_features);
  }
  std::stable_sort(order.begin(), order.end(), byResponse);

  ImageFeatures features;
  features.image = image_name;
  features.width = image.cols;
  features.height = image.rows;
  features.keypoints.reserve(order.size());
  cv::Mat selected(static_cast<int>(order.size()), 128, CV_32F);
  for (size_t i = 0; i < order.size(); ++i) {
    const cv::KeyPoint& k = keypoints[order[i]];
    Keypoint out;
    // Pixel centres at integers at both scales: x_full + 0.5 = scale * (x_small + 0.5).
    out.x = static_cast<float>(scale * (k.pt.x + 0.5) - 0.5);
    out.y = static_cast<float>(scale * (k.pt.y + 0.5) - 0.5);
    out.size = static_cast<float>(k.size * scale);
    out.angle = k.angle;
    out.response = k.response;
    const int u = std::clamp(static_cast<int>(std::lround(out.x)), 0, image.cols - 1);
    const int v = std::clamp(static_cast<int>(std::lround(out.y)), 0, image.rows - 1);
    if (image.channels() == 1) {
      const uint8_t g = image.at<uint8_t>(v, u);
      out.rgb = {g, g, g};
    } else {
      const uint8_t* bgr = image.ptr<uint8_t>(v) + u * image.channels();
      out.rgb = {bgr[2], bgr[1], bgr[0]};
    }
    features.keypoints.push_back(out);
    descriptors.row(order[i]).copyTo(selected.row(static_cast<int>(i)));
  }
  features.descriptors = quantizeDescriptors(selected, options.root_sift);
  return features;
}

}  // namespace auv::recon::features
