#include "auv/recon/calibration/undistort.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "auv/recon/common/stage_error.h"

namespace auv::recon::calibration {

void UndistortOptions::check() const {
  AUV_RECON_CHECK_OPTION(alpha >= 0 && alpha <= 1, alpha, "must be in [0, 1]");
}

Undistorter::Undistorter(const CameraCalibration& calibration, const UndistortOptions& options)
    : distorted_(calibration.clone()), undistorted_(calibration.clone()) {
  options.check();
  // A new matrix, not `= zeros(...)`: assigning a MatExpr writes into the shared buffer.
  undistorted_.distortion = cv::Mat(cv::Mat::zeros(1, 5, CV_64F));
  identity_ = cv::countNonZero(calibration.distortion != 0) == 0;
  if (identity_) return;
  undistorted_.camera_matrix =
      cv::getOptimalNewCameraMatrix(calibration.camera_matrix, calibration.distortion,
                                    calibration.image_size, options.alpha, calibration.image_size);
  cv::initUndistortRectifyMap(calibration.camera_matrix, calibration.distortion, cv::Mat(),
                              undistorted_.camera_matrix, calibration.image_size, CV_16SC2, map1_,
                              map2_);
}

cv::Mat Undistorter::apply(const cv::Mat& image, int interpolation) const {
  if (image.size() != distorted_.image_size) {
    throw std::invalid_argument("image of " + std::to_string(image.cols) + "x" +
                                std::to_string(image.rows) + " px, calibration of " +
                                std::to_string(distorted_.image_size.width) + "x" +
                                std::to_string(distorted_.image_size.height));
  }
  if (identity_) return image.clone();
  cv::Mat out;
  cv::remap(image, out, map1_, map2_, interpolation, cv::BORDER_CONSTANT);
  return out;
}

}  // namespace auv::recon::calibration
