#pragma once
// A starting guess of a camera's pinhole intrinsics for footage without a calibration: from the
// user's statement, else from EXIF (35 mm equivalent focal length, else focal length and the
// focal-plane resolution), else COLMAP's default (focal = 1.2 x the larger image side). The
// principal point is the image centre; distortion starts at zero. Written by `auv recon import`
// as calibration/<camera>.prior.yaml (OpenCV FileStorage, the keys of calibration/<camera>.yaml
// plus `prior_source`), beside where a real calibration would be.

#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "auv/recon/import/exif.h"

namespace auv::recon::import {

struct PriorOptions {
  double focal_px = 0.0;    ///< stated focal length in px of the upright images (0: not stated)
  double focal_35mm = 0.0;  ///< stated 35 mm equivalent focal length, mm (0: not stated)
  double default_focal_factor = 1.2;  ///< x the larger side when nothing else is known
  /// deg: a focal whose field of view across the larger side falls outside this range is a lie
  /// (EXIF focal 0.1 mm, a sensor of 1 m) and is ignored.
  double min_fov_deg = 3.0, max_fov_deg = 150.0;

  /// Throws OptionError naming the option when a value is out of range.
  void check() const;
};

struct IntrinsicsPrior {
  cv::Size image_size;  ///< px, upright
  double focal_px = 0.0;
  double cx = 0.0, cy = 0.0;  ///< px, OpenCV convention (pixel centres at integers)
  /// Where the focal came from: "stated_focal_px", "stated_35mm", "exif_35mm",
  /// "exif_focal_plane", "default".
  std::string source;
  std::vector<std::string> ignored;  ///< EXIF values not used, and why
};

/// The prior of an upright image of `size` with `exif` (its EXIF read before orientation).
IntrinsicsPrior intrinsicsPrior(const ExifInfo& exif, const cv::Size& size,
                                const PriorOptions& options);

/// Field of view across the larger side, deg.
double fieldOfViewDeg(double focal_px, const cv::Size& size);

void writeIntrinsicsPrior(const std::filesystem::path& file, const IntrinsicsPrior& prior);
/// Read with the calibration reader (same format). Throws StageError(stage, ...) naming the file
/// and key when it cannot be read.
IntrinsicsPrior readIntrinsicsPrior(const std::filesystem::path& file, const std::string& stage);

}  // namespace auv::recon::import
