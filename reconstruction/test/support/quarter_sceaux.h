#pragma once
// Test data shared by the reconstruction's tests.

#include <filesystem>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "auv/recon/common/survey.h"

namespace auv::recon::test_support {

/// Sceaux castle at quarter resolution as corrected/castle/ (+ castle.yaml); false if absent.
inline bool quarterSceaux(const Survey& survey) {
  namespace fs = std::filesystem;
  const fs::path data = fs::path(AUV_RECON_SHARED_DATA) / "sceaux_castle" / "images";
  if (!fs::exists(data / "K.txt")) return false;
  fs::create_directories(survey.corrected() / "castle");
  for (const auto& entry : fs::directory_iterator(data)) {
    if (entry.path().extension() != ".JPG") continue;
    cv::Mat full = cv::imread(entry.path().string(), cv::IMREAD_COLOR), small;
    cv::resize(full, small, cv::Size(708, 532), 0, 0, cv::INTER_AREA);
    cv::imwrite((survey.corrected() / "castle" / (entry.path().stem().string() + ".png")).string(),
                small);
  }
  cv::FileStorage storage((survey.corrected() / "castle.yaml").string(), cv::FileStorage::WRITE);
  const double f = 2905.88 / 4, cx = (1416 + 0.5) / 4 - 0.5, cy = (1064 + 0.5) / 4 - 0.5;
  storage << "image_width" << 708 << "image_height" << 532;
  storage << "camera_matrix" << (cv::Mat_<double>(3, 3) << f, 0, cx, 0, f, cy, 0, 0, 1);
  storage << "distortion_coefficients" << cv::Mat::zeros(1, 5, CV_64F);
  return true;
}

}  // namespace auv::recon::test_support
