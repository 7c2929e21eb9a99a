// Benchmark helper (issue 20): what a pinhole calibration (a K matrix without distortion terms)
// of a lens finds, so that a self-calibrated lens (sparse/<camera>.yaml: focal + k1 k2) can be
// compared like for like with a data set's K-only "known" focal. A strongly distorted lens has
// no single pinhole focal: OpenCV's cv::calibrateCamera, K only, is run on synthetic boards
// whose points cover the frame as seen through the lens, with the aspect ratio free and fixed;
// the spread between the two is part of the answer.
//
//   pinhole_of_lens --calibration sparse/cam.yaml [--reference-focal 2905.88]
//                   [--out bench_results/pinhole_of_lens.json]
#include <cmath>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>

#include "auv/recon/calibration/calibration.h"
#include "auv/recon/scene/camera.h"

namespace fs = std::filesystem;
using namespace auv::recon;

namespace {

struct Boards {
  std::vector<std::vector<cv::Point3f>> points;  // board frame, z = 0
  std::vector<std::vector<cv::Point2f>> pixels;  // where the lens images them
};

/// Five boards at 5 m, tilted up to 23°, each covering the whole frame with a 32 × 24 grid.
Boards boardsThrough(const scene::Camera& lens) {
  Boards boards;
  for (double tilt : {-0.35, -0.15, 0.0, 0.2, 0.4}) {
    const Eigen::Matrix3d rotation = (Eigen::AngleAxisd(tilt, Eigen::Vector3d::UnitY()) *
                                      Eigen::AngleAxisd(0.5 * tilt, Eigen::Vector3d::UnitX()))
                                         .toRotationMatrix();
    const Eigen::Vector3d centre(0, 0, 5);
    const Eigen::Vector3d normal = rotation.col(2);
    std::vector<cv::Point3f> board;
    std::vector<cv::Point2f> seen;
    for (int row = 0; row < 24; ++row) {
      for (int col = 0; col < 32; ++col) {
        const Eigen::Vector2d pixel((col + 0.5) / 32 * lens.width - 0.5,
                                    (row + 0.5) / 24 * lens.height - 0.5);
        const Eigen::Vector2d n = lens.pixelToNormalized(pixel);
        const Eigen::Vector3d ray(n.x(), n.y(), 1);
        const Eigen::Vector3d hit = ray * (normal.dot(centre) / normal.dot(ray));
        const Eigen::Vector3d on_board = rotation.transpose() * (hit - centre);
        board.emplace_back(on_board.x(), on_board.y(), 0.f);
        seen.emplace_back(pixel.x(), pixel.y());
      }
    }
    boards.points.push_back(board);
    boards.pixels.push_back(seen);
  }
  return boards;
}

nlohmann::json pinholeCalibration(const scene::Camera& lens, const Boards& boards,
                                  bool fix_aspect) {
  cv::Mat K = (cv::Mat_<double>(3, 3) << lens.fx, 0, lens.cx, 0, lens.fy, lens.cy, 0, 0, 1);
  cv::Mat distortion = cv::Mat::zeros(5, 1, CV_64F);
  std::vector<cv::Mat> rvecs, tvecs;
  int flags = cv::CALIB_USE_INTRINSIC_GUESS | cv::CALIB_FIX_PRINCIPAL_POINT |
              cv::CALIB_ZERO_TANGENT_DIST | cv::CALIB_FIX_K1 | cv::CALIB_FIX_K2 | cv::CALIB_FIX_K3;
  if (fix_aspect) flags |= cv::CALIB_FIX_ASPECT_RATIO;
  const double rms =
      cv::calibrateCamera(boards.points, boards.pixels, cv::Size(lens.width, lens.height), K,
                          distortion, rvecs, tvecs, flags);
  return {{"fx", K.at<double>(0, 0)}, {"fy", K.at<double>(1, 1)}, {"rms_px", rms}};
}

}  // namespace

int main(int argc, char** argv) {
  fs::path calibration_file, out;
  double reference = 0;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string key = argv[i];
    if (key == "--calibration") {
      calibration_file = argv[i + 1];
    } else if (key == "--reference-focal") {
      reference = std::stod(argv[i + 1]);
    } else if (key == "--out") {
      out = argv[i + 1];
    } else {
      std::cerr << "pinhole_of_lens: unknown option " << key << "\n";
      return 2;
    }
  }
  if (calibration_file.empty()) {
    std::cerr << "usage: pinhole_of_lens --calibration FILE.yaml [--reference-focal PX] "
                 "[--out FILE.json]\n";
    return 2;
  }
  try {
    const calibration::CameraCalibration calibration =
        calibration::readCalibration(calibration_file, "pinhole_of_lens");
    const cv::Mat& K = calibration.camera_matrix;
    scene::Camera lens = scene::Camera::pinhole(
        1, calibration.image_size.width, calibration.image_size.height, K.at<double>(0, 0),
        K.at<double>(1, 1), K.at<double>(0, 2), K.at<double>(1, 2));
    lens.model = scene::CameraModel::OPENCV;
    lens.distortion.assign(calibration.distortion.begin<double>(),
                           calibration.distortion.end<double>());
    const Boards boards = boardsThrough(lens);
    nlohmann::json result = {
        {"calibration", calibration_file.string()},
        {"lens", {{"fx", lens.fx}, {"fy", lens.fy}, {"distortion", lens.distortion}}},
        {"pinhole_aspect_free", pinholeCalibration(lens, boards, false)},
        {"pinhole_aspect_fixed", pinholeCalibration(lens, boards, true)}};
    std::cout << "lens: fx " << lens.fx << " px, fy " << lens.fy << " px\n";
    for (const char* fit : {"pinhole_aspect_free", "pinhole_aspect_fixed"}) {
      const nlohmann::json& r = result[fit];
      std::cout << fit << ": fx " << r["fx"].get<double>() << " px, fy " << r["fy"].get<double>()
                << " px, rms " << r["rms_px"].get<double>() << " px";
      if (reference > 0) {
        std::cout << " (fx " << 100 * (r["fx"].get<double>() / reference - 1) << " %, fy "
                  << 100 * (r["fy"].get<double>() / reference - 1) << " % from " << reference
                  << ")";
      }
      std::cout << "\n";
    }
    if (reference > 0) {
      result["reference_focal"] = reference;
      std::cout << "lens fx " << 100 * (lens.fx / reference - 1) << " % from " << reference << "\n";
    }
    if (!out.empty()) {
      std::ofstream(out) << result.dump(2) << "\n";
    }
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";  // names the file (StageError)
    return 1;
  }
  return 0;
}
