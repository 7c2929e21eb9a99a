#include "auv/recon/calibration/calibrate_stage.h"

#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "auv/recon/common/option_set.h"
#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"

namespace fs = std::filesystem;

namespace auv::recon::calibration {

void CalibrateStageOptions::check() const {
  if (camera.empty()) throw std::invalid_argument("--camera: required");
  if (camera.find('/') != std::string::npos || camera[0] == '.') {
    throw std::invalid_argument("--camera " + camera + ": must be a camera name");
  }
  if (input.empty()) throw std::invalid_argument("--input: required (video or folder)");
  calibration.check();
}

void CalibrateStageOptions::bind(OptionSet& set) {
  CalibrationOptions& o = calibration;
  set.add("camera", &camera, "camera id (required): the file is calibration/<camera>.yaml");
  set.add("input", &input,
          "chessboard video (.mp4 .avi .mov .mkv) or folder of chessboard images (required)");
  set.add("board_columns", &o.board_columns, "inner corners along a board row");
  set.add("board_rows", &o.board_rows, "inner corners along a board column");
  set.add("square_size_m", &o.square_size_m, "m, side of a square");
  set.add("max_views", &o.max_views, "boards calibrated at most");
  set.add("min_views", &o.min_views, "boards needed");
  set.add("detection_width", &o.detection_width,
          "px: boards searched on a copy this wide (0 = full size)");
  set.add("subpix_window", &o.subpix_window, "px: half size of the cornerSubPix window");
  set.add("fix_k3", &o.fix_k3, "estimate k1 k2 p1 p2 only");
  set.add("zero_tangential", &o.zero_tangential, "p1 = p2 = 0");
  set.add("outlier_view_factor", &o.outlier_view_factor,
          "drop views with RMS above this x the median view's and solve again (0 = off)");
}

CalibrateStageResult runCalibrateStage(const Survey& survey, const CalibrateStageOptions& options) {
  options.check();
  std::error_code error;
  if (!fs::exists(options.input, error)) {
    throw StageError("calibrate", options.input + ": no such video or folder");
  }
  CalibrateStageResult result;
  result.calibration = fs::is_directory(options.input)
                           ? calibrateFromImages(options.input, options.calibration)
                           : calibrateFromVideo(options.input, options.calibration);
  result.file = survey.calibrationFile(options.camera);
  const CameraCalibration& c = result.calibration;
  writeCalibration(result.file, c, options.calibration);
  const cv::Mat& K = c.camera_matrix;
  std::vector<double> distortion(c.distortion.begin<double>(), c.distortion.end<double>());
  nlohmann::json section = readReportSection(survey.report(), "calibrate");
  section[options.camera] = {{"input", options.input},
                             {"views_used", c.views_used},
                             {"views_tried", c.views_tried},
                             {"views_dropped", c.dropped},
                             {"rms_reprojection_error_px", c.rms_px},
                             {"fx", K.at<double>(0, 0)},
                             {"fy", K.at<double>(1, 1)},
                             {"cx", K.at<double>(0, 2)},
                             {"cy", K.at<double>(1, 2)},
                             {"distortion", distortion}};
  updateReport(survey.report(), "calibrate", section);
  return result;
}

StageReport CalibrateStage::runWith(const Survey& survey,
                                    const CalibrateStageOptions& options) const {
  const CalibrateStageResult result = runCalibrateStage(survey, options);
  const CameraCalibration& c = result.calibration;
  const cv::Mat& K = c.camera_matrix;
  std::ostringstream line;
  line << "calibrate: " << options.camera << ": " << c.views_used << " boards of " << c.views_tried
       << " views";
  if (!c.dropped.empty()) line << " (" << c.dropped.size() << " outliers dropped)";
  line << ", RMS reprojection error " << c.rms_px << " px, fx " << K.at<double>(0, 0) << " fy "
       << K.at<double>(1, 1) << " cx " << K.at<double>(0, 2) << " cy " << K.at<double>(1, 2)
       << " -> " << result.file.string();
  StageReport report;
  report.lines.push_back(line.str());
  report.summary = options.camera + ": RMS " + std::to_string(c.rms_px) + " px";
  return report;
}

}  // namespace auv::recon::calibration
