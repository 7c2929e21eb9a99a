#pragma once
// Chessboard calibration of one camera (paper section 3.3: "we pre-calibrate the intrinsic
// parameters of the cameras in an underwater environment prior to the mission using a
// calibration pattern and a standard calibration procedure [56]" = Zhang's method, as OpenCV's
// cv::calibrateCamera implements it). The flat port's refraction is absorbed by the radial
// distortion terms (section 3.3, [54]).

#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "auv/recon/scene/camera.h"

namespace auv::recon::calibration {

struct CalibrationOptions {
  int board_columns = 9;        ///< inner corners along a row of the chessboard
  int board_rows = 6;           ///< inner corners along a column
  double square_size_m = 0.06;  ///< m; only scales the board poses, not the intrinsics
  /// Views calibrated at most: a video is sampled evenly down to this many frames, an image
  /// folder uses every image (the first `max_views` with a board are kept).
  int max_views = 40;
  int min_views = 5;  ///< fewer boards found is a stage failure
  /// Boards are searched on a copy at most this wide (px; 0 = full size) and the corners
  /// refined with cv::cornerSubPix on the full image: the search is the slow part.
  int detection_width = 1000;
  int subpix_window = 5;         ///< px, half size of the cornerSubPix window (full image)
  bool fix_k3 = false;           ///< estimate k1 k2 p1 p2 only (k3 = 0): for few or flat views
  bool zero_tangential = false;  ///< p1 = p2 = 0
  /// Views whose RMS error exceeds this many times the median view's are dropped and the
  /// camera calibrated again once (a misdetected board). 0 = keep every view.
  double outlier_view_factor = 3.0;

  /// Throws OptionError naming the field and its value.
  void check() const;
};

/// The intrinsics of one camera, as `calibration/<camera>.yaml` stores them.
struct CameraCalibration {
  cv::Size image_size;               ///< px
  cv::Mat camera_matrix;             ///< 3x3 CV_64F, OpenCV pixel convention (centres at integers)
  cv::Mat distortion;                ///< 1xN CV_64F, OpenCV order k1 k2 p1 p2 [k3 ...]
  double rms_px = 0;                 ///< RMS reprojection error over all corners of the views used
  int views_used = 0;                ///< boards the result comes from
  int views_tried = 0;               ///< frames or images searched
  std::vector<std::string> views;    ///< names of the views used ("frame 12", "left01.jpg")
  std::vector<double> view_rms_px;   ///< per used view
  std::vector<std::string> dropped;  ///< outlier views removed before the final solve
  /// Set when these intrinsics are a starting guess, not a calibration (`prior_source` of the
  /// import's calibration/<camera>.prior.yaml: "exif_35mm", "default", ...): SfM refines them.
  std::string prior_source;

  /// A deep copy (copying the struct shares the cv::Mat buffers).
  CameraCalibration clone() const;
};

/// Inner-corner positions of the board in one image (full-resolution px), refined to
/// sub-pixel; empty when the board is not found. `gray` is CV_8UC1.
std::vector<cv::Point2f> findBoard(const cv::Mat& gray, const CalibrationOptions& options);

/// Zhang calibration from detected boards (`corners[i]` of view `names[i]`), with one round of
/// outlier-view removal. Throws StageError("calibrate", ...) with too few views.
CameraCalibration calibrateFromCorners(const std::vector<std::vector<cv::Point2f>>& corners,
                                       const std::vector<std::string>& names, cv::Size image_size,
                                       const CalibrationOptions& options);

/// Calibrates from every image of a folder (.png .jpg .jpeg .bmp .tif .tiff). Throws
/// StageError naming the folder (missing, no images, too few boards) or the image (unreadable,
/// another size than the first).
CameraCalibration calibrateFromImages(const std::filesystem::path& folder,
                                      const CalibrationOptions& options);

/// Calibrates from a chessboard video, streamed and sampled evenly (at most `max_views`
/// frames searched twice over). Throws StageError naming the video.
CameraCalibration calibrateFromVideo(const std::filesystem::path& video,
                                     const CalibrationOptions& options);

/// `calibration/<camera>.yaml` (OpenCV FileStorage): image_width, image_height, camera_matrix,
/// distortion_coefficients, rms_reprojection_error_px (+ views_used, board size). Written
/// through a temporary name: an earlier file is replaced only by a complete one.
void writeCalibration(const std::filesystem::path& file, const CameraCalibration& calibration,
                      const CalibrationOptions& options);

/// Reads what writeCalibration writes (the extra keys are optional). Throws StageError(stage,
/// ...) naming the file and the missing or malformed key.
CameraCalibration readCalibration(const std::filesystem::path& file, const std::string& stage);

/// The pinhole camera of undistorted images (`corrected/<camera>.yaml`, which the correct
/// stage writes) with id `id`. Throws StageError(stage, ...) naming the file when it cannot be
/// read (readCalibration) or has non-zero distortion_coefficients.
/// The calibration of a model's camera: its matrix and (up to five) OpenCV distortion
/// coefficients, e.g. a lens that sfm self-calibrated.
CameraCalibration calibrationOf(const scene::Camera& camera);

scene::Camera readUndistortedCamera(const std::filesystem::path& file, uint32_t id,
                                    const std::string& stage);

}  // namespace auv::recon::calibration
