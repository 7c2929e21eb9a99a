#include "auv/recon/color/correct_stage.h"

#include <chrono>
#include <memory>
#include <optional>
#include <sstream>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "auv/recon/calibration/calibration.h"
#include "auv/recon/common/option_set.h"
#include "auv/recon/common/progress.h"
#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/staged_output.h"

namespace fs = std::filesystem;

namespace auv::recon::color {

namespace {
const char* kStage = "correct";

nlohmann::json intrinsicsJson(const calibration::CameraCalibration& c) {
  const cv::Mat& K = c.camera_matrix;
  return {{"width", c.image_size.width}, {"height", c.image_size.height},
          {"fx", K.at<double>(0, 0)},    {"fy", K.at<double>(1, 1)},
          {"cx", K.at<double>(0, 2)},    {"cy", K.at<double>(1, 2)}};
}
}  // namespace

void CorrectStageOptions::check() const {
  color.check();
  undistort.check();
  AUV_RECON_CHECK_OPTION(png_compression >= 0 && png_compression <= 9, png_compression,
                         "must be in [0, 9]");
  AUV_RECON_CHECK_OPTION(undistort_images || correct_colors, correct_colors,
                         "nothing to do with both --no-undistort and --no-correct-colors");
  for (const auto& camera : cameras) {
    AUV_RECON_CHECK_OPTION(
        !camera.empty() && camera.find('/') == std::string::npos && camera[0] != '.', camera,
        "must be a camera folder name");
  }
}

void CorrectStageOptions::bind(OptionSet& set) {
  set.add("camera", &cameras, "camera id (folder of keyframes/); repeatable; all");
  set.add("undistort", &undistort_images,
          "undistort with calibration/<camera>.yaml (--no-undistort: keep the distortion)");
  set.add("correct_colors", &correct_colors,
          "lαβ colour correction (--no-correct-colors: undistortion only)");
  set.add("chroma_strength", &color.chroma_strength,
          "fraction of the α, β shift to the white point applied (0-1)");
  set.add("cutoff_low", &color.cutoff_low,
          "fraction of the pixels cut off at the dark end of the luminance");
  set.add("cutoff_high", &color.cutoff_high,
          "fraction of the pixels cut off at the bright end of the luminance");
  set.add("stretch_luminance", &color.stretch_luminance,
          "luminance cut-off and stretch (--no-stretch-luminance: off)");
  set.add("alpha", &undistort.alpha,
          "0: undistorted images hold valid pixels only; 1: every source pixel kept");
  set.add("png_compression", &png_compression, "PNG compression level 0-9");
}

CorrectStageResult runCorrectStage(const Survey& survey, const CorrectStageOptions& options) {
  options.check();
  const auto start = std::chrono::steady_clock::now();
  Survey::requireExists(survey.keyframes(), kStage, "keyframes");
  std::vector<std::string> cameras = options.cameras;
  if (cameras.empty()) cameras = Survey::cameraFolders(survey.keyframes(), kStage);

  // Everything each camera needs is checked before the first image is written.
  struct Work {
    std::string camera;
    std::vector<fs::path> images;
    std::optional<calibration::CameraCalibration> calibration;
    fs::path intrinsics_file;  ///< calibration/<camera>.yaml, or the import's .prior.yaml
    std::unique_ptr<calibration::Undistorter> undistorter;
  };
  std::vector<Work> work;
  size_t total = 0;
  for (const auto& camera : cameras) {
    Work w;
    w.camera = camera;
    const fs::path folder = survey.keyframes() / camera;
    std::error_code error;
    if (!fs::is_directory(folder, error)) {
      throw StageError(kStage, "camera '" + camera + "': " + folder.string() +
                                   " not found (run `auv recon keyframes` first)");
    }
    w.images = listFiles(folder, {".png"});
    if (w.images.empty()) {
      throw StageError(kStage,
                       "camera '" + camera + "': " + folder.string() + ": no keyframes (.png)");
    }
    const fs::path calibration_file = survey.calibrationFile(camera);
    // Without a calibration, the prior `auv recon import` wrote (EXIF or stated focal, no
    // distortion) gives the intrinsics: nothing to undistort with, and the images stay as taken.
    const fs::path prior_file = survey.calibration() / (camera + ".prior.yaml");
    const bool has_calibration = fs::exists(calibration_file, error);
    const bool has_prior = !has_calibration && fs::exists(prior_file, error);
    if (options.undistort_images && !has_calibration && !has_prior) {
      throw StageError(kStage, "camera '" + camera +
                                   "': no calibration: " + calibration_file.string() +
                                   " not found (run `auv recon calibrate " +
                                   survey.root().string() + " --camera " + camera +
                                   " --input <chessboard video or folder>`, import the footage "
                                   "with `auv recon import` for an intrinsics prior, or pass "
                                   "--no-undistort to keep the lens distortion)");
    }
    if (has_calibration || has_prior) {
      w.intrinsics_file = has_calibration ? calibration_file : prior_file;
      w.calibration = calibration::readCalibration(w.intrinsics_file, kStage);
    }
    if (options.undistort_images && has_calibration) {
      w.undistorter = std::make_unique<calibration::Undistorter>(*w.calibration, options.undistort);
    }
    total += w.images.size();
    work.push_back(std::move(w));
  }

  CorrectStageResult result;
  std::vector<std::unique_ptr<StagedOutput>> outputs;
  Progress progress("correct", "images", total);
  const std::vector<int> png{cv::IMWRITE_PNG_COMPRESSION, options.png_compression};
  for (auto& w : work) {
    const auto camera_start = std::chrono::steady_clock::now();
    outputs.push_back(std::make_unique<StagedOutput>(survey.corrected() / w.camera));
    CameraCorrection camera;
    camera.camera = w.camera;
    camera.undistorted = w.undistorter && !w.undistorter->identity();
    for (const auto& file : w.images) {
      cv::Mat image = cv::imread(file.string(), cv::IMREAD_COLOR);
      if (image.empty()) throw StageError(kStage, file.string() + ": not a readable image");
      if (w.calibration && image.size() != w.calibration->image_size) {
        throw StageError(kStage, file.string() + ": " + std::to_string(image.cols) + "x" +
                                     std::to_string(image.rows) + " px, but " +
                                     w.intrinsics_file.string() + " is for " +
                                     std::to_string(w.calibration->image_size.width) + "x" +
                                     std::to_string(w.calibration->image_size.height));
      }
      if (w.undistorter) image = w.undistorter->apply(image);
      if (options.correct_colors) {
        CorrectedImage corrected = correctColor(image, options.color);
        camera.mean_alpha += corrected.statistics.mean_alpha;
        camera.mean_beta += corrected.statistics.mean_beta;
        image = std::move(corrected.image);
      }
      const fs::path out = outputs.back()->path() / file.filename();
      if (!cv::imwrite(out.string(), image, png)) {
        throw StageError(kStage, out.string() + ": cannot write");
      }
      ++camera.images;
      progress.advance();
    }
    // The frame index (times, scores) travels with the images.
    const fs::path index = survey.keyframes() / w.camera / "index.csv";
    std::error_code error;
    if (fs::exists(index, error)) {
      fs::copy_file(index, outputs.back()->path() / "index.csv", error);
      if (error) throw StageError(kStage, index.string() + ": cannot copy: " + error.message());
    }
    camera.mean_alpha /= camera.images;
    camera.mean_beta /= camera.images;
    camera.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - camera_start).count();
    result.cameras.push_back(camera);
  }
  progress.finish();
  for (auto& output : outputs) output->commit();
  calibration::CalibrationOptions board;  // board keys of the yaml: defaults, informative only
  // The report keeps the cameras of earlier runs that this one did not redo.
  nlohmann::json cameras_json =
      readReportSection(survey.report(), kStage).value("cameras", nlohmann::json::object());
  if (!cameras_json.is_object()) cameras_json = nlohmann::json::object();
  for (size_t i = 0; i < work.size(); ++i) {
    const Work& w = work[i];
    const fs::path yaml = survey.corrected() / (w.camera + ".yaml");
    nlohmann::json camera = {{"images", result.cameras[i].images},
                             {"undistorted", result.cameras[i].undistorted},
                             {"mean_alpha_removed", result.cameras[i].mean_alpha},
                             {"mean_beta_removed", result.cameras[i].mean_beta},
                             {"seconds", result.cameras[i].seconds},
                             {"intrinsics_file", w.intrinsics_file.string()}};
    if (w.undistorter) {
      calibration::writeCalibration(yaml, w.undistorter->undistorted(), board);
      camera["intrinsics"] = intrinsicsJson(w.undistorter->undistorted());
    } else if (w.calibration) {
      calibration::writeCalibration(yaml, *w.calibration, board);  // still distorted, or a prior
      camera["intrinsics"] = intrinsicsJson(*w.calibration);
    } else {
      std::error_code error;
      fs::remove(yaml, error);  // an older one would describe other images
      camera["intrinsics"] = nullptr;
    }
    cameras_json[w.camera] = camera;
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  nlohmann::json section = {{"cameras", cameras_json},
                            {"seconds", result.seconds},
                            {"options",
                             {{"chroma_strength", options.color.chroma_strength},
                              {"cutoff_low", options.color.cutoff_low},
                              {"cutoff_high", options.color.cutoff_high},
                              {"stretch_luminance", options.color.stretch_luminance},
                              {"correct_colors", options.correct_colors},
                              {"undistort", options.undistort_images},
                              {"alpha", options.undistort.alpha}}}};
  updateReport(survey.report(), kStage, section);
  return result;
}

StageReport CorrectStage::runWith(const Survey& survey, const CorrectStageOptions& options) const {
  const CorrectStageResult result = runCorrectStage(survey, options);
  StageReport report;
  int images = 0;
  for (const auto& camera : result.cameras) {
    std::ostringstream line;
    line << "correct: " << camera.camera << ": " << camera.images << " images"
         << (camera.undistorted ? ", undistorted" : ", not undistorted")
         << ", mean cast removed (alpha, beta) = (" << camera.mean_alpha << ", " << camera.mean_beta
         << ")";
    report.lines.push_back(line.str());
    images += camera.images;
  }
  std::ostringstream done;
  done << "correct: done in " << result.seconds << " s -> " << survey.corrected().string();
  report.lines.push_back(done.str());
  report.summary = std::to_string(images) + " images corrected";
  return report;
}

}  // namespace auv::recon::color
