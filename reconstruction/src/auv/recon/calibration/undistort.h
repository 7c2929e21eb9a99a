#pragma once
// Distortion correction of the keyframes with the pre-calibrated intrinsics (paper section 3.3):
// the images handed to SfM are pinhole images whose intrinsics stay fixed.

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "auv/recon/calibration/calibration.h"

namespace auv::recon::calibration {

struct UndistortOptions {
  /// cv::getOptimalNewCameraMatrix's free scaling: 0 = the output holds valid pixels only
  /// (the pin-cushion borders are cropped and the rest enlarged), 1 = every source pixel is
  /// kept (black corners). Same output size as the input.
  double alpha = 0.0;

  /// Throws OptionError naming the field and its value.
  void check() const;
};

/// Remaps images of one camera to the pinhole camera `undistorted()` (maps computed once).
class Undistorter {
 public:
  Undistorter(const CameraCalibration& calibration, const UndistortOptions& options);

  /// The intrinsics of the output images: same size, new camera matrix, zero distortion.
  const CameraCalibration& undistorted() const { return undistorted_; }
  const CameraCalibration& distorted() const { return distorted_; }
  /// True when the calibration has no distortion: images pass through unchanged.
  bool identity() const { return identity_; }

  /// `image` must have the calibration's size (throws std::invalid_argument otherwise).
  /// `interpolation`: cv::INTER_LINEAR for images, cv::INTER_NEAREST for masks and labels.
  cv::Mat apply(const cv::Mat& image, int interpolation = cv::INTER_LINEAR) const;

 private:
  CameraCalibration distorted_, undistorted_;
  cv::Mat map1_, map2_;
  bool identity_ = false;
};

}  // namespace auv::recon::calibration
