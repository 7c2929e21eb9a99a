#include "auv/recon/masks/mask.h"

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "auv/recon/calibration/calibration.h"
#include "auv/recon/calibration/undistort.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/scene/colmap_text.h"

namespace fs = std::filesystem;

namespace auv::recon::masks {
namespace {

std::string sizeText(cv::Size size) {
  return std::to_string(size.width) + "x" + std::to_string(size.height) + " px";
}

bool isFile(const fs::path& file) {
  std::error_code error;
  return fs::is_regular_file(file, error);
}

}  // namespace

fs::path masksFolder(const Survey& survey) { return survey.root() / "masks"; }

fs::path cameraMaskFile(const Survey& survey, const std::string& camera) {
  return masksFolder(survey) / (camera + ".png");
}

fs::path imageMaskFile(const Survey& survey, const std::string& camera,
                       const std::string& image_file) {
  return masksFolder(survey) / camera / (image_file + ".png");
}

std::optional<fs::path> findMask(const Survey& survey, const std::string& camera,
                                 const std::string& image_file) {
  const fs::path own = imageMaskFile(survey, camera, image_file);
  if (isFile(own)) return own;
  const fs::path shared = cameraMaskFile(survey, camera);
  if (isFile(shared)) return shared;
  return std::nullopt;
}

cv::Mat loadMask(const fs::path& file, cv::Size expected, const std::string& stage,
                 const std::string& image_description) {
  cv::Mat mask;
  try {
    mask = cv::imread(file.string(), cv::IMREAD_GRAYSCALE);
  } catch (const cv::Exception&) {
    mask.release();
  }
  if (mask.empty()) {
    throw StageError(stage, file.string() +
                                ": cannot read the mask (missing, truncated or not an image; "
                                "masks are grey PNGs, zero = ignored)");
  }
  if (!expected.empty() && mask.size() != expected) {
    throw StageError(stage, file.string() + ": mask is " + sizeText(mask.size()) + " but " +
                                (image_description.empty() ? "its image" : image_description) +
                                " is " + sizeText(expected) +
                                " (a mask must have the size of the images it masks)");
  }
  cv::Mat binary;
  cv::compare(mask, 0, binary, cv::CMP_GT);  // 255 where used, 0 where ignored
  return binary;
}

CameraMasks::CameraMasks(const Survey& survey, std::string camera, std::string stage)
    : survey_(survey), camera_(std::move(camera)), stage_(std::move(stage)) {
  std::error_code error;
  any_ = isFile(cameraMaskFile(survey_, camera_)) ||
         fs::is_directory(masksFolder(survey_) / camera_, error);
  if (!any_) return;
  // Undistorted by `correct`: the calibration has distortion, the corrected camera none.
  const fs::path calibration_file = survey_.calibrationFile(camera_);
  const fs::path corrected_file = survey_.corrected() / (camera_ + ".yaml");
  if (!isFile(calibration_file) || !isFile(corrected_file)) return;
  const calibration::CameraCalibration original =
      calibration::readCalibration(calibration_file, stage_);
  const calibration::CameraCalibration corrected =
      calibration::readCalibration(corrected_file, stage_);
  const bool distorted = cv::countNonZero(original.distortion != 0) > 0;
  const bool undistorted = cv::countNonZero(corrected.distortion != 0) == 0;
  if (!distorted || !undistorted || original.image_size != corrected.image_size) return;
  cv::initUndistortRectifyMap(original.camera_matrix, original.distortion, cv::Mat(),
                              corrected.camera_matrix, original.image_size, CV_32FC1, map_x_,
                              map_y_);
}

cv::Mat CameraMasks::toCorrected(const cv::Mat& mask) const {
  if (map_x_.empty() || mask.size() != map_x_.size()) return mask;
  cv::Mat out;
  // Outside the original frame (black corners of alpha > 0): nothing to use there.
  cv::remap(mask, out, map_x_, map_y_, cv::INTER_NEAREST, cv::BORDER_CONSTANT, cv::Scalar(0));
  return out;
}

cv::Mat CameraMasks::forImage(const std::string& image_file, cv::Size size) const {
  if (!any_) return cv::Mat();
  const std::string what = "image " + camera_ + "/" + image_file;
  const fs::path own = imageMaskFile(survey_, camera_, image_file);
  if (isFile(own)) return toCorrected(loadMask(own, size, stage_, what));
  const fs::path shared = cameraMaskFile(survey_, camera_);
  if (!isFile(shared)) return cv::Mat();
  std::lock_guard<std::mutex> lock(mutex_);
  cv::Mat& cached = camera_mask_[{size.width, size.height}];
  if (cached.empty()) cached = toCorrected(loadMask(shared, size, stage_, what));
  return cached;
}

SurveyMasks::SurveyMasks(const Survey& survey, std::string stage)
    : survey_(survey), stage_(std::move(stage)) {
  if (survey_.pinholeWorkspace().images != survey_.undistorted()) return;
  std::error_code error;
  if (!fs::is_directory(masksFolder(survey_), error)) return;  // nothing to remap
  scene::Reconstruction model;
  try {
    model = scene::readColmapText(survey_.sparse());
  } catch (const std::exception& e) {
    throw StageError(stage_, "cannot read " + survey_.sparse().string() +
                                 " to remap the masks onto undistorted/: " + e.what());
  }
  // The same lens maps as sfm's undistorted images (sfm/undistorted_model.cc).
  std::map<uint32_t, std::shared_ptr<const calibration::Undistorter>> by_camera;
  for (const auto& [id, camera] : model.cameras) {
    if (!camera.hasDistortion()) continue;
    by_camera[id] = std::make_shared<const calibration::Undistorter>(
        calibration::calibrationOf(camera), calibration::UndistortOptions());
  }
  for (const auto& [id, image] : model.images) {
    const auto lens = by_camera.find(image.camera_id);
    if (lens != by_camera.end()) lenses_[image.name] = lens->second;
  }
}

SurveyMasks::~SurveyMasks() = default;

cv::Mat SurveyMasks::forImage(const std::string& relative_name, cv::Size size) const {
  const fs::path name(relative_name);
  const std::string camera = name.has_parent_path() ? name.parent_path().string() : "";
  std::shared_ptr<const CameraMasks> masks;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto& entry = cameras_[camera];
    if (!entry) entry = std::make_shared<const CameraMasks>(survey_, camera, stage_);
    masks = entry;
  }
  cv::Mat mask = masks->forImage(name.filename().string(), size);
  const auto lens = lenses_.find(relative_name);
  if (!mask.empty() && lens != lenses_.end()) {
    // Pixels from outside the frame come out 0: ignored, as the corners of toCorrected().
    try {
      mask = lens->second->apply(mask, cv::INTER_NEAREST);
    } catch (const std::invalid_argument& e) {
      throw StageError(stage_, "mask of " + relative_name + " for undistorted/: " + e.what());
    }
  }
  if (!mask.empty()) {
    std::lock_guard<std::mutex> lock(mutex_);
    masked_.insert(relative_name);
  }
  return mask;
}

size_t SurveyMasks::masked() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return masked_.size();
}

}  // namespace auv::recon::masks
