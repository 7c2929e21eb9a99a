#include "auv/recon/calibration/calibration.h"

#include <algorithm>
#include <cmath>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/staged_output.h"
#include "auv/recon/common/survey.h"

namespace fs = std::filesystem;

namespace auv::recon::calibration {

namespace {
const char* kStage = "calibrate";

std::vector<cv::Point3f> boardPoints(const CalibrationOptions& options) {
  std::vector<cv::Point3f> points;
  for (int r = 0; r < options.board_rows; ++r) {
    for (int c = 0; c < options.board_columns; ++c) {
      points.emplace_back(static_cast<float>(c * options.square_size_m),
                          static_cast<float>(r * options.square_size_m), 0.f);
    }
  }
  return points;
}

cv::Mat toGray(const cv::Mat& image) {
  if (image.channels() == 1) return image;
  cv::Mat gray;
  cv::cvtColor(image, gray, image.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
  return gray;
}

double median(std::vector<double> values) {
  if (values.empty()) return 0;
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  return values[mid];
}

struct Solve {
  double rms = 0;
  cv::Mat K, dist;
  std::vector<double> view_rms;
};

Solve solve(const std::vector<std::vector<cv::Point2f>>& corners, cv::Size size,
            const CalibrationOptions& options) {
  const std::vector<std::vector<cv::Point3f>> object(corners.size(), boardPoints(options));
  int flags = 0;
  if (options.fix_k3) flags |= cv::CALIB_FIX_K3;
  if (options.zero_tangential) flags |= cv::CALIB_ZERO_TANGENT_DIST;
  Solve s;
  std::vector<cv::Mat> rvecs, tvecs;
  cv::Mat std_intrinsics, std_extrinsics, per_view;
  s.rms = cv::calibrateCamera(
      object, corners, size, s.K, s.dist, rvecs, tvecs, std_intrinsics, std_extrinsics, per_view,
      flags, cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-10));
  for (int i = 0; i < per_view.rows; ++i) s.view_rms.push_back(per_view.at<double>(i));
  return s;
}

/// StageError naming the source when too few boards were found.
void requireViews(size_t found, size_t tried, const CalibrationOptions& options,
                  const fs::path& source) {
  if (static_cast<int>(found) >= options.min_views) return;
  throw StageError(kStage, source.string() + ": the " + std::to_string(options.board_columns) +
                               "x" + std::to_string(options.board_rows) +
                               " chessboard (inner corners) was found in " + std::to_string(found) +
                               " of " + std::to_string(tried) + " images searched, need at least " +
                               std::to_string(options.min_views) + " (min_views)");
}
}  // namespace

CameraCalibration CameraCalibration::clone() const {
  CameraCalibration copy = *this;
  copy.camera_matrix = camera_matrix.clone();
  copy.distortion = distortion.clone();
  return copy;
}

void CalibrationOptions::check() const {
  AUV_RECON_CHECK_OPTION(board_columns >= 2, board_columns, "must be >= 2 inner corners");
  AUV_RECON_CHECK_OPTION(board_rows >= 2, board_rows, "must be >= 2 inner corners");
  AUV_RECON_CHECK_OPTION(board_columns != board_rows, board_columns,
                         "must differ from board_rows (a square board's orientation is ambiguous)");
  AUV_RECON_CHECK_OPTION(square_size_m > 0 && std::isfinite(square_size_m), square_size_m,
                         "must be > 0 (m)");
  AUV_RECON_CHECK_OPTION(min_views >= 3, min_views, "must be >= 3 (Zhang's method)");
  AUV_RECON_CHECK_OPTION(max_views >= min_views, max_views, "must be >= min_views");
  AUV_RECON_CHECK_OPTION(detection_width == 0 || detection_width >= 200, detection_width,
                         "must be 0 (full size) or >= 200 px");
  AUV_RECON_CHECK_OPTION(subpix_window >= 1 && subpix_window <= 30, subpix_window,
                         "must be in [1, 30] px");
  AUV_RECON_CHECK_OPTION(outlier_view_factor == 0 || outlier_view_factor >= 1.5,
                         outlier_view_factor, "must be 0 (off) or >= 1.5");
}

std::vector<cv::Point2f> findBoard(const cv::Mat& gray, const CalibrationOptions& options) {
  const cv::Size pattern(options.board_columns, options.board_rows);
  double scale = 1.0;
  cv::Mat search = gray;
  if (options.detection_width > 0 && gray.cols > options.detection_width) {
    scale = static_cast<double>(options.detection_width) / gray.cols;
    cv::resize(gray, search, cv::Size(), scale, scale, cv::INTER_AREA);
  }
  std::vector<cv::Point2f> corners;
  // The quick check first (rejects most frames without a board at once); it also rejects
  // many low-contrast underwater boards, which the full search and then the sector-based
  // detector (cv::findChessboardCornersSB, more robust to blur and low contrast) still find.
  const int flags = cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE;
  const bool found =
      cv::findChessboardCorners(search, pattern, corners, flags | cv::CALIB_CB_FAST_CHECK) ||
      cv::findChessboardCorners(search, pattern, corners, flags) ||
      cv::findChessboardCornersSB(search, pattern, corners,
                                  cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_EXHAUSTIVE);
  if (!found) return {};
  if (scale != 1.0) {
    // Corners of the reduced copy back to the full image (pixel centres at integers).
    for (auto& p : corners) {
      p.x = static_cast<float>((p.x + 0.5) / scale - 0.5);
      p.y = static_cast<float>((p.y + 0.5) / scale - 0.5);
    }
  }
  // The refinement window must stay within one square: at most ~40% of the smallest spacing.
  double spacing = 1e9;
  for (int r = 0; r < options.board_rows; ++r) {
    for (int c = 0; c + 1 < options.board_columns; ++c) {
      const int i = r * options.board_columns + c;
      spacing = std::min(spacing, cv::norm(corners[i + 1] - corners[i]));
    }
  }
  const int window = std::max(1, std::min(options.subpix_window, static_cast<int>(spacing * 0.4)));
  cv::cornerSubPix(gray, corners, cv::Size(window, window), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS | cv::TermCriteria::COUNT, 40, 0.01));
  return corners;
}

CameraCalibration calibrateFromCorners(const std::vector<std::vector<cv::Point2f>>& corners,
                                       const std::vector<std::string>& names, cv::Size image_size,
                                       const CalibrationOptions& options) {
  options.check();
  if (corners.size() != names.size()) {
    throw std::invalid_argument("calibrateFromCorners: corners and names differ in size");
  }
  if (static_cast<int>(corners.size()) < options.min_views) {
    throw StageError(kStage, "the " + std::to_string(options.board_columns) + "x" +
                                 std::to_string(options.board_rows) + " board was found in " +
                                 std::to_string(corners.size()) + " views, need at least " +
                                 std::to_string(options.min_views) + " (min_views)");
  }
  const size_t expected = static_cast<size_t>(options.board_columns * options.board_rows);
  for (size_t i = 0; i < corners.size(); ++i) {
    if (corners[i].size() != expected) {
      throw std::invalid_argument("calibrateFromCorners: view " + names[i] + " has " +
                                  std::to_string(corners[i].size()) + " corners, expected " +
                                  std::to_string(expected));
    }
  }
  CameraCalibration result;
  result.image_size = image_size;
  std::vector<std::vector<cv::Point2f>> kept = corners;
  std::vector<std::string> kept_names = names;
  Solve s = solve(kept, image_size, options);
  if (options.outlier_view_factor > 0) {
    // One round: a misdetected board (corners shifted by a row) has an error far above the rest.
    const double limit = options.outlier_view_factor * std::max(median(s.view_rms), 0.05);
    std::vector<std::vector<cv::Point2f>> inliers;
    std::vector<std::string> inlier_names;
    for (size_t i = 0; i < kept.size(); ++i) {
      if (s.view_rms[i] <= limit) {
        inliers.push_back(kept[i]);
        inlier_names.push_back(kept_names[i]);
      } else {
        result.dropped.push_back(kept_names[i]);
      }
    }
    if (!result.dropped.empty() && static_cast<int>(inliers.size()) >= options.min_views) {
      kept = std::move(inliers);
      kept_names = std::move(inlier_names);
      s = solve(kept, image_size, options);
    } else {
      result.dropped.clear();
    }
  }
  result.camera_matrix = s.K;
  result.distortion = s.dist.reshape(1, 1);
  result.rms_px = s.rms;
  result.views_used = static_cast<int>(kept.size());
  result.views = kept_names;
  result.view_rms_px = s.view_rms;
  return result;
}

CameraCalibration calibrateFromImages(const fs::path& folder, const CalibrationOptions& options) {
  options.check();
  std::error_code error;
  if (!fs::is_directory(folder, error)) {
    throw StageError(kStage, folder.string() + ": no such folder of chessboard images");
  }
  const auto files = listFiles(folder, {".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff"});
  if (files.empty()) {
    throw StageError(kStage, folder.string() +
                                 ": no images (.png .jpg .jpeg .bmp .tif .tiff) to calibrate from");
  }
  std::vector<std::vector<cv::Point2f>> corners;
  std::vector<std::string> names;
  cv::Size size;
  for (const auto& file : files) {
    const cv::Mat image = cv::imread(file.string(), cv::IMREAD_GRAYSCALE);
    if (image.empty()) throw StageError(kStage, file.string() + ": not a readable image");
    if (size.empty()) size = image.size();
    if (image.size() != size) {
      throw StageError(kStage, file.string() + ": " + std::to_string(image.cols) + "x" +
                                   std::to_string(image.rows) + " px, but " +
                                   files.front().filename().string() + " is " +
                                   std::to_string(size.width) + "x" + std::to_string(size.height) +
                                   " (one camera per folder)");
    }
    if (static_cast<int>(corners.size()) >= options.max_views) continue;
    auto found = findBoard(image, options);
    if (!found.empty()) {
      corners.push_back(std::move(found));
      names.push_back(file.filename().string());
    }
  }
  requireViews(corners.size(), files.size(), options, folder);
  CameraCalibration result = calibrateFromCorners(corners, names, size, options);
  result.views_tried = static_cast<int>(files.size());
  return result;
}

CameraCalibration calibrateFromVideo(const fs::path& video, const CalibrationOptions& options) {
  options.check();
  std::error_code error;
  if (!fs::is_regular_file(video, error)) {
    throw StageError(kStage, video.string() + ": no such video");
  }
  cv::VideoCapture capture(video.string(), cv::CAP_FFMPEG);
  if (!capture.isOpened()) {
    throw StageError(kStage, video.string() + ": cannot open the video (damaged or not a video)");
  }
  const double reported = capture.get(cv::CAP_PROP_FRAME_COUNT);
  const int count = reported > 0 ? static_cast<int>(reported) : 0;
  // Search twice as many frames as views wanted: some show no complete board.
  const int step = count > 0 ? std::max(1, count / (2 * options.max_views)) : 1;
  std::vector<std::vector<cv::Point2f>> corners;
  std::vector<std::string> names;
  cv::Size size;
  int tried = 0;
  cv::Mat frame;
  for (int index = 0;; ++index) {
    if (index % step != 0) {
      if (!capture.grab()) break;
      continue;
    }
    if (!capture.read(frame) || frame.empty()) break;
    if (size.empty()) size = frame.size();
    ++tried;
    auto found = findBoard(toGray(frame), options);
    if (!found.empty()) {
      corners.push_back(std::move(found));
      names.push_back("frame " + std::to_string(index));
    }
  }
  if (tried == 0) throw StageError(kStage, video.string() + ": no frame could be decoded");
  if (static_cast<int>(corners.size()) > options.max_views) {
    // Keep views spread over the whole sequence.
    std::vector<std::vector<cv::Point2f>> spread;
    std::vector<std::string> spread_names;
    for (int i = 0; i < options.max_views; ++i) {
      const size_t k = static_cast<size_t>(i) * corners.size() / options.max_views;
      spread.push_back(corners[k]);
      spread_names.push_back(names[k]);
    }
    corners = std::move(spread);
    names = std::move(spread_names);
  }
  requireViews(corners.size(), static_cast<size_t>(tried), options, video);
  CameraCalibration result = calibrateFromCorners(corners, names, size, options);
  result.views_tried = tried;
  return result;
}

void writeCalibration(const fs::path& file, const CameraCalibration& c,
                      const CalibrationOptions& options) {
  cv::FileStorage fs("calibration.yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY |
                                             cv::FileStorage::FORMAT_YAML);
  fs << "image_width" << c.image_size.width;
  fs << "image_height" << c.image_size.height;
  fs << "camera_matrix" << c.camera_matrix;
  fs << "distortion_coefficients" << c.distortion;
  fs << "rms_reprojection_error_px" << c.rms_px;
  fs << "views_used" << c.views_used;
  fs << "board_columns" << options.board_columns;
  fs << "board_rows" << options.board_rows;
  fs << "square_size_m" << options.square_size_m;
  if (!c.prior_source.empty()) fs << "prior_source" << c.prior_source;
  const std::string text = fs.releaseAndGetString();
  std::error_code error;
  if (file.has_parent_path()) fs::create_directories(file.parent_path(), error);
  writeFileAtomically(file, text);
}

CameraCalibration readCalibration(const fs::path& file, const std::string& stage) {
  std::error_code error;
  if (!fs::is_regular_file(file, error)) {
    throw StageError(stage, file.string() + ": no such calibration file");
  }
  cv::FileStorage fs;
  try {
    if (!fs.open(file.string(), cv::FileStorage::READ)) {
      throw StageError(stage, file.string() + ": not an OpenCV FileStorage file");
    }
  } catch (const cv::Exception& e) {
    throw StageError(stage, file.string() + ": not an OpenCV FileStorage file (" + e.err + ")");
  }
  auto need = [&](const char* key) {
    const cv::FileNode node = fs[key];
    if (node.empty()) throw StageError(stage, file.string() + ": missing key '" + key + "'");
    return node;
  };
  CameraCalibration c;
  try {
    c.image_size.width = static_cast<int>(need("image_width"));
    c.image_size.height = static_cast<int>(need("image_height"));
    need("camera_matrix") >> c.camera_matrix;
    need("distortion_coefficients") >> c.distortion;
    if (!fs["rms_reprojection_error_px"].empty()) {
      c.rms_px = static_cast<double>(fs["rms_reprojection_error_px"]);
    }
    if (!fs["views_used"].empty()) c.views_used = static_cast<int>(fs["views_used"]);
    if (!fs["prior_source"].empty()) fs["prior_source"] >> c.prior_source;
  } catch (const cv::Exception& e) {
    throw StageError(stage, file.string() + ": malformed (" + e.err + ")");
  }
  if (c.image_size.width <= 0 || c.image_size.height <= 0) {
    throw StageError(stage, file.string() + ": image_width/image_height must be > 0");
  }
  if (c.camera_matrix.rows != 3 || c.camera_matrix.cols != 3) {
    throw StageError(stage, file.string() + ": camera_matrix must be 3x3");
  }
  c.camera_matrix.convertTo(c.camera_matrix, CV_64F);
  if (c.camera_matrix.at<double>(0, 0) <= 0 || c.camera_matrix.at<double>(1, 1) <= 0) {
    throw StageError(stage, file.string() + ": camera_matrix focal lengths must be > 0");
  }
  const int n = static_cast<int>(c.distortion.total());
  if (n != 0 && n != 4 && n != 5 && n != 8 && n != 12 && n != 14) {
    throw StageError(stage, file.string() +
                                ": distortion_coefficients must have 0, 4, 5, 8, "
                                "12 or 14 values (OpenCV order), got " +
                                std::to_string(n));
  }
  if (n == 0) {
    c.distortion = cv::Mat(cv::Mat::zeros(1, 5, CV_64F));
  } else {
    c.distortion = c.distortion.reshape(1, 1);
    c.distortion.convertTo(c.distortion, CV_64F);
  }
  return c;
}

CameraCalibration calibrationOf(const scene::Camera& camera) {
  CameraCalibration c;
  c.image_size = cv::Size(camera.width, camera.height);
  c.camera_matrix =
      (cv::Mat_<double>(3, 3) << camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
  c.distortion = cv::Mat::zeros(1, 5, CV_64F);
  for (size_t i = 0; i < camera.distortion.size() && i < 5; ++i) {
    c.distortion.at<double>(0, static_cast<int>(i)) = camera.distortion[i];
  }
  return c;
}

scene::Camera readUndistortedCamera(const fs::path& file, uint32_t id, const std::string& stage) {
  const CameraCalibration c = readCalibration(file, stage);
  if (cv::countNonZero(c.distortion != 0) > 0) {
    throw StageError(stage, file.string() +
                                ": non-zero distortion_coefficients (the intrinsics of undistorted "
                                "images are expected: zeros)");
  }
  const cv::Mat& k = c.camera_matrix;
  return scene::Camera::pinhole(id, c.image_size.width, c.image_size.height, k.at<double>(0, 0),
                                k.at<double>(1, 1), k.at<double>(0, 2), k.at<double>(1, 2));
}

}  // namespace auv::recon::calibration
