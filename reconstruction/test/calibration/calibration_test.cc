// Calibration and undistortion (paper section 3.3): chessboard images rendered through a known
// camera with lens distortion, the real chessboard photos of Debian's opencv-doc, the
// calibration file format and its errors, and the undistortion maps.
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "auv/recon/calibration/calibration.h"
#include "auv/recon/calibration/undistort.h"
#include "auv/recon/common/stage_error.h"

namespace fs = std::filesystem;
using namespace auv::recon;
using namespace auv::recon::calibration;

namespace {

const cv::Size kSize(640, 480);
const cv::Matx33d kK(600, 0, 322.5, 0, 604, 236.0, 0, 0, 1);
// Mild pin-cushion like a flat port (the simulator's default is k1 0.08, k2 0.02).
const cv::Matx<double, 1, 5> kDistortion(0.10, 0.03, 0.0008, -0.0005, 0.0);
constexpr double kSquare = 0.03;  // m

fs::path freshFolder(const std::string& name) {
  const fs::path folder = fs::temp_directory_path() /
                          ("auv_recon_calibration_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(folder);
  fs::create_directories(folder);
  return folder;
}

/// Renders views of a 9x6 (inner corners) chessboard through kK + kDistortion: for each of 4x4
/// sub-pixel samples the ray (from cv::undistortPoints) is intersected with the board plane.
class BoardRenderer {
 public:
  static constexpr int kSamples = 4;  ///< per pixel side (anti-aliasing)

  BoardRenderer() {
    std::vector<cv::Point2f> pixels;
    for (int y = 0; y < kSize.height; ++y) {
      for (int x = 0; x < kSize.width; ++x) {
        for (int s = 0; s < kSamples * kSamples; ++s) {
          pixels.emplace_back(x + ((s % kSamples) + 0.5f) / kSamples - 0.5f,
                              y + ((s / kSamples) + 0.5f) / kSamples - 0.5f);
        }
      }
    }
    cv::undistortPoints(
        pixels, rays_, kK, kDistortion, cv::noArray(), cv::noArray(),
        cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 50, 1e-10));
  }

  cv::Mat render(const cv::Vec3d& rvec, const cv::Vec3d& tvec) const {
    cv::Matx33d R;
    cv::Rodrigues(rvec, R);
    const cv::Vec3d n(R(0, 2), R(1, 2), R(2, 2));
    cv::Mat image(kSize, CV_8UC1);
    for (int y = 0; y < kSize.height; ++y) {
      for (int x = 0; x < kSize.width; ++x) {
        double sum = 0;
        for (int s = 0; s < kSamples * kSamples; ++s) {
          const cv::Point2f& r =
              rays_[(static_cast<size_t>(y) * kSize.width + x) * kSamples * kSamples + s];
          const cv::Vec3d d(r.x, r.y, 1.0);
          const double depth = n.dot(tvec) / n.dot(d);
          const cv::Vec3d board = R.t() * (depth * d - tvec);
          const double u = board[0] / kSquare, v = board[1] / kSquare;
          double value = 90;                                       // background
          if (u >= -2 && u < 10 && v >= -2 && v < 7) value = 235;  // white margin
          if (u >= -1 && u < 9 && v >= -1 && v < 6) {
            const int parity =
                (static_cast<int>(std::floor(u)) + static_cast<int>(std::floor(v))) & 1;
            value = parity ? 235 : 25;
          }
          sum += value;
        }
        image.at<uchar>(y, x) = cv::saturate_cast<uchar>(sum / (kSamples * kSamples));
      }
    }
    return image;
  }

 private:
  std::vector<cv::Point2f> rays_;
};

/// Board poses 0.5 m away over a 3x3 grid of the image (the corners too, where the distortion
/// is largest), tilted ~0.3 rad in turn about each axis, plus three centred steep views.
std::vector<std::pair<cv::Vec3d, cv::Vec3d>> poses() {
  std::vector<std::pair<cv::Vec3d, cv::Vec3d>> p;
  const double tilts[][3] = {{0.3, 0.0, 0.0},  {0.0, 0.3, 0.1},     {-0.3, 0.0, -0.1},
                             {0.0, -0.3, 0.0}, {0.25, 0.25, 0.2},   {-0.25, 0.25, 0},
                             {0.25, -0.25, 0}, {-0.25, -0.25, 0.1}, {0.1, 0.1, -0.2},
                             {0.55, 0.0, 0.0}, {0.0, 0.55, 0.3},    {-0.4, 0.4, 0.0}};
  const double centres[][2] = {{-0.22, -0.15}, {0, -0.15}, {0.22, -0.15}, {-0.22, 0},
                               {0, 0},         {0.22, 0},  {-0.22, 0.15}, {0, 0.15},
                               {0.22, 0.15},   {0, 0},     {0.02, 0},     {0, 0.02}};
  for (int i = 0; i < 12; ++i) {
    const cv::Vec3d rvec(tilts[i][0], tilts[i][1], tilts[i][2]);
    // The board's middle (4 x 2.5 squares from its first corner) on the ray of `centres`.
    cv::Matx33d R;
    cv::Rodrigues(rvec, R);
    const cv::Vec3d middle = R * cv::Vec3d(4 * kSquare, 2.5 * kSquare, 0);
    const double z = i < 9 ? 0.5 : 0.42;
    const cv::Vec3d tvec = cv::Vec3d(centres[i][0] * z, centres[i][1] * z, z) - middle;
    p.emplace_back(rvec, tvec);
  }
  return p;
}

}  // namespace

TEST(Calibration, RecoversKnownIntrinsicsFromRenderedBoards) {
  const fs::path folder = freshFolder("rendered");
  BoardRenderer renderer;
  const auto views = poses();
  for (size_t i = 0; i < views.size(); ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "board%02zu.png", i);
    cv::imwrite((folder / name).string(), renderer.render(views[i].first, views[i].second));
  }
  CalibrationOptions options;
  options.square_size_m = kSquare;
  const CameraCalibration result = calibrateFromImages(folder, options);
  EXPECT_EQ(result.views_tried, 12);
  EXPECT_GE(result.views_used, 10);
  EXPECT_LT(result.rms_px, 0.3);
  const cv::Mat& K = result.camera_matrix;
  // Stated tolerances: focal lengths 0.5 %, principal point 2 px, k1 0.02, k2 0.05.
  EXPECT_NEAR(K.at<double>(0, 0), kK(0, 0), 0.005 * kK(0, 0));
  EXPECT_NEAR(K.at<double>(1, 1), kK(1, 1), 0.005 * kK(1, 1));
  EXPECT_NEAR(K.at<double>(0, 2), kK(0, 2), 2.0);
  EXPECT_NEAR(K.at<double>(1, 2), kK(1, 2), 2.0);
  ASSERT_EQ(result.distortion.cols, 5);
  EXPECT_NEAR(result.distortion.at<double>(0), kDistortion(0), 0.02);
  EXPECT_NEAR(result.distortion.at<double>(1), kDistortion(1), 0.05);
  // What matters for undistortion: the distortion model agrees with the truth across the
  // image within 1 px, where the distortion moves points by up to ~30 px (the corner
  // detections themselves are off by 0.05-0.1 px on average on these renderings).
  std::vector<cv::Point3f> rays;
  for (float x = -0.45f; x <= 0.451f; x += 0.05f) {  // the part of the image the boards cover
    for (float y = -0.3f; y <= 0.301f; y += 0.05f) rays.emplace_back(x, y, 1.f);
  }
  std::vector<cv::Point2f> truth, estimate;
  cv::projectPoints(rays, cv::Vec3d(), cv::Vec3d(), kK, kDistortion, truth);
  cv::projectPoints(rays, cv::Vec3d(), cv::Vec3d(), K, result.distortion, estimate);
  double worst = 0;
  for (size_t i = 0; i < truth.size(); ++i)
    worst = std::max(worst, cv::norm(truth[i] - estimate[i]));
  EXPECT_LT(worst, 1.0);
  fs::remove_all(folder);
}

TEST(Calibration, RecoversIntrinsicsFromNoisyProjections) {
  // Corners projected exactly, plus 0.2 px Gaussian noise: Zhang's method on the detections.
  std::vector<cv::Point3f> board;
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 9; ++c) board.emplace_back(c * kSquare, r * kSquare, 0);
  }
  cv::RNG rng(3);
  std::vector<std::vector<cv::Point2f>> corners;
  std::vector<std::string> names;
  for (const auto& [rvec, tvec] : poses()) {
    std::vector<cv::Point2f> projected;
    cv::projectPoints(board, rvec, tvec, kK, kDistortion, projected);
    for (auto& p : projected) p += cv::Point2f(rng.gaussian(0.2), rng.gaussian(0.2));
    corners.push_back(projected);
    names.push_back("view " + std::to_string(names.size()));
  }
  CalibrationOptions options;
  options.square_size_m = kSquare;
  const CameraCalibration result = calibrateFromCorners(corners, names, kSize, options);
  EXPECT_NEAR(result.rms_px, 0.2 * std::sqrt(2.0), 0.08);  // RMS of the 2D noise
  EXPECT_NEAR(result.camera_matrix.at<double>(0, 0), kK(0, 0), 0.01 * kK(0, 0));
  EXPECT_NEAR(result.camera_matrix.at<double>(0, 2), kK(0, 2), 3.0);

  // A misdetected board (corners shifted by one square) is dropped as an outlier view.
  corners[3] = corners[4];
  std::rotate(corners[3].begin(), corners[3].begin() + 9, corners[3].end());
  const CameraCalibration cleaned = calibrateFromCorners(corners, names, kSize, options);
  ASSERT_EQ(cleaned.dropped.size(), 1u);
  EXPECT_EQ(cleaned.dropped[0], "view 3");
  EXPECT_LT(cleaned.rms_px, 0.5);
}

TEST(Calibration, RealChessboardPhotosOfOpencvDoc) {
  const fs::path data = "/usr/share/doc/opencv-doc/examples/data";
  if (!fs::exists(data / "left01.jpg")) {
    GTEST_SKIP() << data << "/left01.jpg absent: install opencv-doc (scripts/install-deps.sh)";
  }
  const fs::path folder = freshFolder("opencv_doc");
  int images = 0;
  for (int i = 1; i <= 14; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "left%02d.jpg", i);
    if (fs::exists(data / name)) {
      fs::create_symlink(data / name, folder / name);
      ++images;
    }
  }
  CalibrationOptions options;
  options.square_size_m = 0.025;
  const CameraCalibration result = calibrateFromImages(folder, options);
  EXPECT_EQ(result.views_tried, images);
  EXPECT_GE(result.views_used, images - 2);
  EXPECT_EQ(result.image_size, cv::Size(640, 480));
  // OpenCV's own calibration sample reports fx ~ 532-537 px and an RMS error ~ 0.4 px on these.
  EXPECT_LT(result.rms_px, 0.6);
  EXPECT_NEAR(result.camera_matrix.at<double>(0, 0), 535, 15);
  EXPECT_NEAR(result.camera_matrix.at<double>(1, 1), 535, 15);
  EXPECT_NEAR(result.camera_matrix.at<double>(0, 2), 340, 15);
  EXPECT_NEAR(result.camera_matrix.at<double>(1, 2), 235, 15);
  fs::remove_all(folder);
}

TEST(Calibration, TooFewBoardsAndEmptyFoldersNameTheSource) {
  const fs::path folder = freshFolder("few");
  try {
    calibrateFromImages(folder, CalibrationOptions());
    FAIL() << "an empty folder was accepted";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find(folder.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("no images"), std::string::npos) << e.what();
  }
  BoardRenderer renderer;
  const auto views = poses();
  for (int i = 0; i < 2; ++i) {
    cv::imwrite((folder / ("b" + std::to_string(i) + ".png")).string(),
                renderer.render(views[i].first, views[i].second));
  }
  cv::imwrite((folder / "blank.png").string(), cv::Mat(kSize, CV_8UC1, cv::Scalar(128)));
  try {
    calibrateFromImages(folder, CalibrationOptions());
    FAIL() << "two boards were accepted";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("found in 2 of 3"), std::string::npos) << e.what();
  }
  cv::imwrite((folder / "small.png").string(), cv::Mat(100, 100, CV_8UC1, cv::Scalar(128)));
  try {
    calibrateFromImages(folder, CalibrationOptions());
    FAIL() << "images of two sizes were accepted";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("small.png"), std::string::npos) << e.what();
  }
  EXPECT_THROW(calibrateFromVideo(folder / "missing.mp4", CalibrationOptions()), StageError);
  std::ofstream(folder / "garbage.mp4") << std::string(3000, 'x');
  EXPECT_THROW(calibrateFromVideo(folder / "garbage.mp4", CalibrationOptions()), StageError);
  CalibrationOptions bad;
  bad.board_rows = 9;
  EXPECT_THROW(bad.check(), OptionError);
  fs::remove_all(folder);
}

TEST(CalibrationFile, RoundTripAndErrorsNameTheFileAndKey) {
  const fs::path folder = freshFolder("file");
  CameraCalibration c;
  c.image_size = kSize;
  c.camera_matrix = cv::Mat(kK);
  c.distortion = cv::Mat(kDistortion);
  c.rms_px = 0.31;
  c.views_used = 12;
  const fs::path file = folder / "calibration" / "left.yaml";
  writeCalibration(file, c, CalibrationOptions());
  const CameraCalibration back = readCalibration(file, "correct");
  EXPECT_EQ(back.image_size, kSize);
  EXPECT_EQ(cv::norm(back.camera_matrix, cv::Mat(kK)), 0.0);
  EXPECT_EQ(cv::norm(back.distortion, cv::Mat(kDistortion)), 0.0);
  EXPECT_DOUBLE_EQ(back.rms_px, 0.31);
  // The keys of the survey conventions are all there.
  cv::FileStorage fs(file.string(), cv::FileStorage::READ);
  for (const char* key : {"image_width", "image_height", "camera_matrix", "distortion_coefficients",
                          "rms_reprojection_error_px"}) {
    EXPECT_FALSE(fs[key].empty()) << key;
  }
  fs.release();

  try {
    readCalibration(folder / "none.yaml", "correct");
    FAIL();
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("none.yaml"), std::string::npos) << e.what();
  }
  const fs::path partial = folder / "partial.yaml";
  std::ofstream(partial) << "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\n";
  try {
    readCalibration(partial, "correct");
    FAIL();
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("camera_matrix"), std::string::npos) << e.what();
  }
  const fs::path garbage = folder / "garbage.yaml";
  std::ofstream(garbage) << "{{{ not yaml";
  EXPECT_THROW(readCalibration(garbage, "correct"), StageError);
  fs::remove_all(folder);
}

TEST(Undistorter, MapsADistortedPointToItsPinholeProjection) {
  CameraCalibration c;
  c.image_size = kSize;
  c.camera_matrix = cv::Mat(kK);
  c.distortion = cv::Mat(kDistortion);
  const Undistorter undistorter(c, UndistortOptions());
  EXPECT_FALSE(undistorter.identity());
  const cv::Mat K_new = undistorter.undistorted().camera_matrix;
  EXPECT_EQ(cv::countNonZero(undistorter.undistorted().distortion), 0);
  // Points near the corners, where pin-cushion distortion moves them the most.
  for (const cv::Point3f ray : {cv::Point3f(-0.4f, -0.3f, 1), cv::Point3f(0.42f, 0.28f, 1),
                                cv::Point3f(0.05f, -0.02f, 1), cv::Point3f(-0.38f, 0.3f, 1)}) {
    std::vector<cv::Point2f> distorted;
    cv::projectPoints(std::vector<cv::Point3f>{ray}, cv::Vec3d(), cv::Vec3d(), kK, kDistortion,
                      distorted);
    cv::Mat image(kSize, CV_8UC1, cv::Scalar(0));
    cv::circle(image, distorted[0] * 16, 2 * 16, cv::Scalar(255), cv::FILLED, cv::LINE_AA, 4);
    const cv::Mat out = undistorter.apply(image);
    const cv::Moments m = cv::moments(out);
    ASSERT_GT(m.m00, 0);
    const cv::Point2d found(m.m10 / m.m00, m.m01 / m.m00);
    const cv::Point2d expected(K_new.at<double>(0, 0) * ray.x + K_new.at<double>(0, 2),
                               K_new.at<double>(1, 1) * ray.y + K_new.at<double>(1, 2));
    EXPECT_LT(cv::norm(found - expected), 0.5) << "ray " << ray;
  }
  EXPECT_THROW(undistorter.apply(cv::Mat(10, 10, CV_8UC1)), std::invalid_argument);
  // alpha 0: every output pixel comes from inside the source image (no black border).
  const cv::Mat white = undistorter.apply(cv::Mat(kSize, CV_8UC1, cv::Scalar(255)));
  cv::Mat inner = white(cv::Rect(2, 2, kSize.width - 4, kSize.height - 4));
  EXPECT_EQ(cv::countNonZero(inner < 250), 0);

  UndistortOptions bad;
  bad.alpha = 2;
  EXPECT_THROW(Undistorter(c, bad), OptionError);
  c.distortion = cv::Mat::zeros(1, 5, CV_64F);
  EXPECT_TRUE(Undistorter(c, UndistortOptions()).identity());
}
