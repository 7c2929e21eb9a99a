#pragma once
// Image masks (COLMAP's convention, colmap.github.io/faq.html "Mask image regions"): a grey PNG
// per image, zero pixels are ignored. Burned-in timestamps, depth read-outs and the vehicle's
// own parts are the same in every frame and would otherwise match in every pair.
//
//   <survey>/masks/<camera>/<image file name>.png   one image (e.g. left_000120.png.png)
//   <survey>/masks/<camera>.png                     every image of the camera
//
// The per-image mask wins. Masks are drawn on the images as the user gave them (keyframes/,
// the original frames); for the undistorted images of corrected/ they are remapped the way the
// `correct` stage remapped the images (nearest neighbour): CameraMasks; for the images of
// undistorted/ (a lens sfm self-calibrated) once more with that lens: SurveyMasks.

#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>

#include <opencv2/core.hpp>

#include "auv/recon/common/survey.h"

namespace auv::recon::calibration {
class Undistorter;
}

namespace auv::recon::masks {

/// <survey>/masks
std::filesystem::path masksFolder(const Survey& survey);
/// <survey>/masks/<camera>.png: the mask of every image of a camera.
std::filesystem::path cameraMaskFile(const Survey& survey, const std::string& camera);
/// <survey>/masks/<camera>/<image file name>.png: the mask of one image.
std::filesystem::path imageMaskFile(const Survey& survey, const std::string& camera,
                                    const std::string& image_file);

/// The mask file of image `image_file` (a file name) of `camera`: the per-image mask if it
/// exists, else the camera's, else none.
std::optional<std::filesystem::path> findMask(const Survey& survey, const std::string& camera,
                                              const std::string& image_file);

/// Reads a mask as 8-bit grey (colour masks are converted, as COLMAP does) and returns it as
/// 0 (ignored) / 255 (used). Throws StageError(stage, ...) naming the file when it cannot be
/// read, and naming the file and both sizes when it is not `expected` large (an empty
/// `expected`: not checked here, the caller checks) (a mask of another
/// resolution belongs to other footage: resizing would misplace it, skipping it would let the
/// overlay poison matching, the thing the mask was made to prevent).
cv::Mat loadMask(const std::filesystem::path& file, cv::Size expected, const std::string& stage,
                 const std::string& image_description = "");

/// The masks of the images of corrected/<camera>/. When the `correct` stage undistorted the
/// camera (calibration/<camera>.yaml with distortion, corrected/<camera>.yaml without), masks
/// are remapped with the same maps (cv::initUndistortRectifyMap from the calibration to the
/// corrected camera matrix, nearest neighbour); pixels that come from outside the original
/// frame are ignored. Thread-safe once built.
class CameraMasks {
 public:
  /// Reads the calibrations (StageError(stage, ...) naming a malformed file).
  CameraMasks(const Survey& survey, std::string camera, std::string stage);

  /// The mask of corrected/<camera>/<image_file>, of `size` px (the corrected image's, which
  /// is the original's); empty when the image has none. Throws StageError as loadMask.
  cv::Mat forImage(const std::string& image_file, cv::Size size) const;
  /// True when the camera has a mask file of either kind.
  bool any() const { return any_; }
  /// True when masks are remapped for undistorted images.
  bool remapped() const { return !map_x_.empty(); }

 private:
  cv::Mat toCorrected(const cv::Mat& mask) const;

  Survey survey_;
  std::string camera_, stage_;
  bool any_ = false;
  cv::Mat map_x_, map_y_;  ///< CV_32F undistortion maps, empty: masks used as drawn
  mutable std::mutex mutex_;
  mutable std::map<std::pair<int, int>, cv::Mat> camera_mask_;  ///< by size, remapped
};

/// The masks of the images of the survey's pinhole workspace (Survey::pinholeWorkspace), by
/// image name (`<camera>/<file>`, the names of the sparse model): those of corrected/, and when
/// sfm wrote undistorted/ for a self-calibrated lens, remapped once more with that lens (the
/// distorted model in sparse/, the same maps as the images, nearest neighbour), so a mask
/// covers the same scene pixels in the images dense and texture read. Thread-safe.
class SurveyMasks {
 public:
  /// Reads sparse/ when the workspace is undistorted/ (StageError(stage, ...) when it cannot).
  SurveyMasks(const Survey& survey, std::string stage);
  ~SurveyMasks();
  /// The mask of `<camera>/<file>` of `size` px; empty when none.
  cv::Mat forImage(const std::string& relative_name, cv::Size size) const;
  /// Distinct images that had a mask so far.
  size_t masked() const;

 private:
  Survey survey_;
  std::string stage_;
  /// Per image name of sparse/: the lens its undistorted/ image was remapped with (only
  /// images of distorted cameras; none when the workspace is sparse/ + corrected/).
  std::map<std::string, std::shared_ptr<const calibration::Undistorter>> lenses_;
  mutable std::mutex mutex_;
  mutable std::map<std::string, std::shared_ptr<const CameraMasks>> cameras_;
  mutable std::set<std::string> masked_;
};

}  // namespace auv::recon::masks
