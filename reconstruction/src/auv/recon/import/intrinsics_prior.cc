#include "auv/recon/import/intrinsics_prior.h"

#include <cmath>
#include <sstream>

#include "auv/recon/calibration/calibration.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/staged_output.h"

namespace fs = std::filesystem;

namespace auv::recon::import {
namespace {

// The diagonal of the 36 x 24 mm frame: a 35 mm equivalent focal length scales the image's
// diagonal (CIPA DC-008), whatever its aspect ratio.
constexpr double kFullFrameDiagonalMm = 43.266615;

std::string number(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

}  // namespace

void PriorOptions::check() const {
  AUV_RECON_CHECK_OPTION(std::isfinite(focal_px) && focal_px >= 0.0, focal_px,
                         "must be >= 0 px (0: not stated)");
  AUV_RECON_CHECK_OPTION(std::isfinite(focal_35mm) && focal_35mm >= 0.0, focal_35mm,
                         "must be >= 0 mm (0: not stated)");
  AUV_RECON_CHECK_OPTION(focal_px == 0.0 || focal_35mm == 0.0, focal_35mm,
                         "state one of focal_px and focal_35mm, not both");
  AUV_RECON_CHECK_OPTION(default_focal_factor > 0.1 && default_focal_factor < 10.0,
                         default_focal_factor, "must be in (0.1, 10) x the larger side");
  AUV_RECON_CHECK_OPTION(min_fov_deg > 0.0 && min_fov_deg < max_fov_deg, min_fov_deg,
                         "must be in (0, max_fov_deg)");
  AUV_RECON_CHECK_OPTION(max_fov_deg < 180.0, max_fov_deg, "must be < 180 deg");
}

double fieldOfViewDeg(double focal_px, const cv::Size& size) {
  return 2.0 * std::atan(0.5 * std::max(size.width, size.height) / focal_px) * 180.0 / M_PI;
}

IntrinsicsPrior intrinsicsPrior(const ExifInfo& exif, const cv::Size& size,
                                const PriorOptions& options) {
  IntrinsicsPrior prior;
  prior.image_size = size;
  prior.cx = 0.5 * (size.width - 1);
  prior.cy = 0.5 * (size.height - 1);
  prior.ignored = exif.ignored;
  const double diagonal = std::hypot(size.width, size.height);
  const auto plausible = [&](double focal, const std::string& what) {
    const double fov = fieldOfViewDeg(focal, size);
    if (fov >= options.min_fov_deg && fov <= options.max_fov_deg) return true;
    prior.ignored.push_back(what + " gives a field of view of " + number(fov) + " deg, outside [" +
                            number(options.min_fov_deg) + ", " + number(options.max_fov_deg) + "]");
    return false;
  };
  const auto take = [&](double focal, const char* source) {
    prior.focal_px = focal;
    prior.source = source;
    return prior;
  };
  // A stated focal is the user's word: only refused when impossible, by check() and here.
  if (options.focal_px > 0.0) return take(options.focal_px, "stated_focal_px");
  if (options.focal_35mm > 0.0) {
    return take(options.focal_35mm * diagonal / kFullFrameDiagonalMm, "stated_35mm");
  }
  if (exif.focal_35mm) {
    const double focal = *exif.focal_35mm * diagonal / kFullFrameDiagonalMm;
    if (plausible(focal, "FocalLengthIn35mmFilm = " + number(*exif.focal_35mm) + " mm")) {
      return take(focal, "exif_35mm");
    }
  }
  if (exif.focal_mm && exif.focal_plane_x_per_mm) {
    // The focal-plane resolution counts pixels of the full-size image (PixelXDimension); an
    // image saved smaller has proportionally fewer.
    double scale = 1.0;
    if (exif.pixel_dimensions) {
      scale = static_cast<double>(std::max(size.width, size.height)) /
              std::max(exif.pixel_dimensions->width, exif.pixel_dimensions->height);
    }
    const double focal = *exif.focal_mm * *exif.focal_plane_x_per_mm * scale;
    if (plausible(focal, "FocalLength = " + number(*exif.focal_mm) + " mm with FocalPlane" +
                             "XResolution = " + number(*exif.focal_plane_x_per_mm) + " px/mm")) {
      return take(focal, "exif_focal_plane");
    }
  }
  return take(options.default_focal_factor * std::max(size.width, size.height), "default");
}

void writeIntrinsicsPrior(const fs::path& file, const IntrinsicsPrior& prior) {
  cv::FileStorage storage("prior.yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY |
                                            cv::FileStorage::FORMAT_YAML);
  const cv::Mat K = (cv::Mat_<double>(3, 3) << prior.focal_px, 0.0, prior.cx, 0.0, prior.focal_px,
                     prior.cy, 0.0, 0.0, 1.0);
  storage << "image_width" << prior.image_size.width;
  storage << "image_height" << prior.image_size.height;
  storage << "camera_matrix" << K;
  storage << "distortion_coefficients" << cv::Mat::zeros(1, 5, CV_64F);
  storage << "prior_source" << prior.source;
  const std::string text = storage.releaseAndGetString();
  std::error_code error;
  if (file.has_parent_path()) fs::create_directories(file.parent_path(), error);
  writeFileAtomically(file, text);
}

IntrinsicsPrior readIntrinsicsPrior(const fs::path& file, const std::string& stage) {
  const calibration::CameraCalibration c = calibration::readCalibration(file, stage);
  IntrinsicsPrior prior;
  prior.image_size = c.image_size;
  prior.focal_px = c.camera_matrix.at<double>(0, 0);
  prior.cx = c.camera_matrix.at<double>(0, 2);
  prior.cy = c.camera_matrix.at<double>(1, 2);
  prior.source = c.prior_source;
  return prior;
}

}  // namespace auv::recon::import
