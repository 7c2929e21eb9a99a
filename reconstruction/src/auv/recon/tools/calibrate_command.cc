// `auv recon calibrate <survey> --camera <id> --input <video|folder>`: chessboard calibration
// (paper section 3.3; calibration/README.md).
#include <filesystem>
#include <iostream>

#include <nlohmann/json.hpp>

#include "auv/recon/calibration/calibration.h"
#include "auv/recon/common/option_set.h"
#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/survey.h"
#include "auv/recon/tools/command.h"

namespace fs = std::filesystem;

namespace auv::recon {
namespace {

int calibrateMain(const std::vector<std::string>& args) {
  return tools::runReportingErrors("calibrate", [&] {
    calibration::CalibrationOptions options;
    std::string survey, camera, input;
    OptionSet set("calibrate");
    set.positional("survey", &survey, "survey folder (writes calibration/<camera>.yaml)");
    set.add("camera", &camera, "camera id (required): the file is calibration/<camera>.yaml");
    set.add("input", &input,
            "chessboard video (.mp4 .avi .mov .mkv) or folder of chessboard images (required)");
    set.add("board_columns", &options.board_columns, "inner corners along a board row");
    set.add("board_rows", &options.board_rows, "inner corners along a board column");
    set.add("square_size_m", &options.square_size_m, "m, side of a square");
    set.add("max_views", &options.max_views, "boards calibrated at most");
    set.add("min_views", &options.min_views, "boards needed");
    set.add("detection_width", &options.detection_width,
            "px: boards searched on a copy this wide (0 = full size)");
    set.add("subpix_window", &options.subpix_window, "px: half size of the cornerSubPix window");
    set.add("fix_k3", &options.fix_k3, "estimate k1 k2 p1 p2 only");
    set.add("zero_tangential", &options.zero_tangential, "p1 = p2 = 0");
    set.add("outlier_view_factor", &options.outlier_view_factor,
            "drop views with RMS above this x the median view's and solve again (0 = off)");
    if (!set.parse(args)) return tools::kExitOk;
    if (camera.empty()) throw std::invalid_argument("--camera: required");
    if (camera.find('/') != std::string::npos || camera[0] == '.') {
      throw std::invalid_argument("--camera " + camera + ": must be a camera name");
    }
    if (input.empty()) throw std::invalid_argument("--input: required (video or folder)");
    options.check();
    std::error_code error;
    if (!fs::exists(input, error)) {
      throw StageError("calibrate", input + ": no such video or folder");
    }
    const calibration::CameraCalibration result =
        fs::is_directory(input) ? calibration::calibrateFromImages(input, options)
                                : calibration::calibrateFromVideo(input, options);
    const Survey s(survey);
    calibration::writeCalibration(s.calibrationFile(camera), result, options);
    const cv::Mat& K = result.camera_matrix;
    std::vector<double> distortion(result.distortion.begin<double>(),
                                   result.distortion.end<double>());
    nlohmann::json section;
    try {
      const nlohmann::json report = readReport(s.report());
      if (report.contains("stages") && report["stages"].contains("calibrate")) {
        section = report["stages"]["calibrate"];
      }
    } catch (const std::exception&) {
    }
    if (!section.is_object()) section = nlohmann::json::object();
    section[camera] = {{"input", input},
                       {"views_used", result.views_used},
                       {"views_tried", result.views_tried},
                       {"views_dropped", result.dropped},
                       {"rms_reprojection_error_px", result.rms_px},
                       {"fx", K.at<double>(0, 0)},
                       {"fy", K.at<double>(1, 1)},
                       {"cx", K.at<double>(0, 2)},
                       {"cy", K.at<double>(1, 2)},
                       {"distortion", distortion}};
    updateReport(s.report(), "calibrate", section);
    std::cout << "calibrate: " << camera << ": " << result.views_used << " boards of "
              << result.views_tried << " views";
    if (!result.dropped.empty()) std::cout << " (" << result.dropped.size() << " outliers dropped)";
    std::cout << ", RMS reprojection error " << result.rms_px << " px, fx " << K.at<double>(0, 0)
              << " fy " << K.at<double>(1, 1) << " cx " << K.at<double>(0, 2) << " cy "
              << K.at<double>(1, 2) << " -> " << s.calibrationFile(camera).string() << std::endl;
    return tools::kExitOk;
  });
}

}  // namespace

AUV_RECON_COMMAND("calibrate", 10,
                  "<survey> --camera <id> --input <video|folder>   chessboard calibration",
                  calibrateMain);

}  // namespace auv::recon
