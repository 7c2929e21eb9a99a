// The calibration sequence is usable for calibration: OpenCV finds the chessboard in most
// frames of the (H.264) video, and calibrating from them recovers the true intrinsics.
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "auv/sim/camera/calibration_sequence.h"
#include "auv/sim/camera/video.h"
#include "camera_test_scenes.h"

namespace auv::sim {
namespace {
namespace fs = std::filesystem;

TEST(CalibrationSequence, ChessboardIsFoundAndRecoversTheIntrinsics) {
  const std::string out = test::freshFolder("calibration");
  CameraOptions camera = CameraOptions::defaults("left");
  camera.width = 480;
  camera.height = 360;
  camera.distortion = {0.1, 0.02, 0, 0, 0};
  CalibrationSequenceOptions options;
  options.frames = 20;
  options.frames_per_pose = 2;
  options.threads = 2;
  options.seed = 3;
  WaterOptics water = WaterOptics::fromVisibility(10.0);
  const CalibrationSequenceReport report =
      renderCalibrationSequence(camera, water, IlluminationOptions{}, options, out);
  EXPECT_EQ(report.frames, 20);
  EXPECT_EQ(report.video_path, out + "/left.mp4");
  ASSERT_TRUE(fs::exists(report.truth_path));
  EXPECT_EQ(readFrameSidecar(VideoRecorder::sidecarPath(report.video_path)).size(), 20u);

  cv::FileStorage truth(report.truth_path, cv::FileStorage::READ);
  cv::Mat K, D;
  int width = 0, height = 0;
  truth["camera_matrix"] >> K;
  truth["distortion_coefficients"] >> D;
  truth["image_width"] >> width;
  truth["image_height"] >> height;
  EXPECT_EQ(width, 480);
  EXPECT_EQ(height, 360);
  const CameraIntrinsics expected = camera.intrinsics();
  EXPECT_NEAR(K.at<double>(0, 0), expected.fx, 1e-9);
  EXPECT_NEAR(D.at<double>(0), 0.1, 1e-12);

  std::vector<cv::Point3f> board;
  for (int j = 0; j < options.board_rows; ++j) {
    for (int i = 0; i < options.board_columns; ++i) {
      board.emplace_back(i * options.square_size, j * options.square_size, 0);
    }
  }
  cv::VideoCapture capture(report.video_path);
  ASSERT_TRUE(capture.isOpened());
  std::vector<std::vector<cv::Point3f>> object_points;
  std::vector<std::vector<cv::Point2f>> image_points;
  int frames = 0;
  for (cv::Mat frame, grey; capture.read(frame); ++frames) {
    cv::cvtColor(frame, grey, cv::COLOR_BGR2GRAY);
    std::vector<cv::Point2f> corners;
    if (cv::findChessboardCorners(grey, {options.board_columns, options.board_rows}, corners)) {
      // A small window: the squares are only ~8-20 px here.
      cv::cornerSubPix(grey, corners, {3, 3}, {-1, -1},
                       {cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 0.01});
      image_points.push_back(corners);
      object_points.push_back(board);
    }
  }
  EXPECT_EQ(frames, 20);
  EXPECT_GE(image_points.size(), 15u) << "the chessboard is found in most frames";

  cv::Mat K_est, D_est;
  std::vector<cv::Mat> rvecs, tvecs;
  // The true lens has no tangential distortion; freeing it would trade off against cx, cy.
  const double rms =
      cv::calibrateCamera(object_points, image_points, {480, 360}, K_est, D_est, rvecs, tvecs,
                          cv::CALIB_FIX_K3 | cv::CALIB_ZERO_TANGENT_DIST);
  EXPECT_LT(rms, 0.5);
  EXPECT_NEAR(K_est.at<double>(0, 0), expected.fx, 0.02 * expected.fx);
  EXPECT_NEAR(K_est.at<double>(1, 1), expected.fy, 0.02 * expected.fy);
  EXPECT_NEAR(K_est.at<double>(0, 2), expected.cx, 4.0);
  EXPECT_NEAR(K_est.at<double>(1, 2), expected.cy, 4.0);
  EXPECT_NEAR(D_est.at<double>(0), 0.1, 0.04);
}

TEST(CalibrationSequence, ChessboardMeshHasTheDocumentedGeometry) {
  const Mesh board = makeChessboardMesh(9, 6, 0.06, 16);
  // 10 x 7 squares plus a one-square white border: 12 x 9 squares.
  EXPECT_NEAR(board.vertices[1].x() - board.vertices[0].x(), 12 * 0.06, 1e-6);
  EXPECT_NEAR(board.vertices[2].y() - board.vertices[1].y(), 9 * 0.06, 1e-6);
  EXPECT_EQ(board.texture.cols, 12 * 16);
  EXPECT_EQ(board.texture.rows, 9 * 16);
  EXPECT_EQ(board.texture.at<cv::Vec3b>(8, 8)[0], 235);           // border: white
  EXPECT_EQ(board.texture.at<cv::Vec3b>(16 + 8, 16 + 8)[0], 20);  // first square: black
  EXPECT_EQ(board.texture.at<cv::Vec3b>(16 + 8, 32 + 8)[0], 235);
  CalibrationSequenceOptions bad;
  bad.frames = 0;
  EXPECT_THROW(bad.check(), std::invalid_argument);
}

}  // namespace
}  // namespace auv::sim
