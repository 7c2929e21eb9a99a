// Videos as the cameras leave them: H.264 MP4 that OpenCV reads back, a sidecar whose times
// follow the frame rate on the camera's own clock, and nothing under the final name unless the
// recording completed.
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/videoio.hpp>

#include "auv/sim/camera/render_run.h"
#include "auv/sim/camera/video.h"
#include "camera_test_scenes.h"

namespace auv::sim {
namespace {
namespace fs = std::filesystem;

cv::Mat testFrame(int index) {
  // A moving gradient, so the encoder has something to encode and frames are tell-apart.
  cv::Mat frame(120, 160, CV_8UC3);
  for (int row = 0; row < frame.rows; ++row) {
    for (int col = 0; col < frame.cols; ++col) {
      frame.at<cv::Vec3b>(row, col) =
          cv::Vec3b(static_cast<uchar>(20 * index), static_cast<uchar>(row + col / 2),
                    static_cast<uchar>(200 - 10 * index));
    }
  }
  return frame;
}

TEST(Video, TenFramesReadBackWithTheirTimes) {
  const std::string folder = test::freshFolder("video_ok");
  const std::string path = folder + "/left/left_0001.mp4";
  CameraOptions camera = CameraOptions::defaults("left");
  camera.frame_rate = 10.0;
  camera.clock_offset = 2.5;
  camera.clock_drift_ppm = 100.0;
  const std::vector<FrameStamp> stamps = cameraFrameTimes(camera, 100.0, 1e9, 10);
  ASSERT_EQ(stamps.size(), 10u);
  {
    VideoRecorder recorder(path, camera.frame_rate, {160, 120});
    EXPECT_EQ(recorder.fourcc(), "avc1");  // H.264 (docs/library-notes.md: available on Debian 12)
    for (const FrameStamp& stamp : stamps) {
      recorder.write(testFrame(static_cast<int>(stamp.frame)), stamp.camera_time, stamp.sim_time);
    }
    EXPECT_FALSE(fs::exists(path));  // not before finish()
    recorder.finish();
  }
  ASSERT_TRUE(fs::exists(path));
  cv::VideoCapture capture(path);
  ASSERT_TRUE(capture.isOpened());
  int frames = 0;
  for (cv::Mat frame; capture.read(frame); ++frames) {
    EXPECT_EQ(frame.size(), cv::Size(160, 120));
    // Lossy, but each frame is recognisably the one written.
    EXPECT_NEAR(cv::mean(frame)[0], cv::mean(testFrame(frames))[0], 4.0) << "frame " << frames;
  }
  EXPECT_EQ(frames, 10);

  const std::vector<FrameStamp> rows = readFrameSidecar(VideoRecorder::sidecarPath(path));
  ASSERT_EQ(rows.size(), 10u);
  const double drift = 1 + 100e-6;
  for (size_t k = 0; k < rows.size(); ++k) {
    EXPECT_EQ(rows[k].frame, static_cast<int64_t>(k));
    // Evenly spaced on the camera's clock, which runs fast and is offset.
    EXPECT_NEAR(rows[k].camera_time, 2.5 + drift * 100.0 + k / 10.0, 2e-6);
    EXPECT_NEAR(rows[k].sim_time, 100.0 + k / (10.0 * drift), 2e-6);
  }
  // Only the two finished files are left.
  int files = 0;
  for (const auto& entry : fs::directory_iterator(folder + "/left")) {
    ++files;
    EXPECT_EQ(entry.path().string().find("incomplete"), std::string::npos) << entry.path();
  }
  EXPECT_EQ(files, 2);
}

TEST(Video, SynchronisedCameraUsesTheSimulationClock) {
  CameraOptions camera = CameraOptions::defaults("forward");
  camera.synchronized = true;
  camera.frame_rate = 4.0;
  const std::vector<FrameStamp> stamps = cameraFrameTimes(camera, 1.0, 2.0);
  ASSERT_EQ(stamps.size(), 5u);  // 1.0, 1.25, ..., 2.0
  for (const FrameStamp& s : stamps) EXPECT_DOUBLE_EQ(s.camera_time, s.sim_time);
  EXPECT_DOUBLE_EQ(stamps.back().sim_time, 2.0);
}

TEST(Video, InterruptedRecordingLeavesNoFileUnderTheFinalName) {
  const std::string folder = test::freshFolder("video_interrupted");
  const std::string path = folder + "/cam.mp4";
  try {
    VideoRecorder recorder(path, 10.0, {160, 120});
    for (int k = 0; k < 3; ++k) recorder.write(testFrame(k), k, k);
    throw std::runtime_error("renderer crashed");  // never reaches finish()
  } catch (const std::runtime_error&) {
  }
  EXPECT_FALSE(fs::exists(path));
  EXPECT_FALSE(fs::exists(VideoRecorder::sidecarPath(path)));
  EXPECT_TRUE(fs::is_empty(folder));  // the temporary files are gone too

  // A frame of the wrong size is an error, not silently dropped.
  {
    VideoRecorder recorder(path, 10.0, {160, 120});
    EXPECT_THROW(recorder.write(cv::Mat(60, 80, CV_8UC3), 0, 0), std::invalid_argument);
  }
  EXPECT_FALSE(fs::exists(path));
  // Nothing written: finish() fails and leaves nothing.
  {
    VideoRecorder recorder(path, 10.0, {160, 120});
    EXPECT_THROW(recorder.finish(), std::runtime_error);
  }
  EXPECT_TRUE(fs::is_empty(folder));
  // A folder that cannot be created names the file.
  try {
    VideoRecorder recorder("/proc/no_such/cam.mp4", 10.0, {160, 120});
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/proc/no_such/cam.mp4"), std::string::npos);
  }
}

}  // namespace
}  // namespace auv::sim
