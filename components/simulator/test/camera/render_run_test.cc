// Rendering a run folder end to end: videos under the recordings folder, sidecars on each
// camera's clock, and COLMAP ground truth that matches the trajectory and the mounting.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/videoio.hpp>
#include <sstream>

#include "auv/sim/camera/camera_rig.h"
#include "auv/sim/camera/render_run.h"
#include "auv/sim/camera/trajectory.h"
#include "auv/sim/world/scenario.h"
#include "camera_test_scenes.h"

namespace auv::sim {
namespace {
namespace fs = std::filesystem;

// A run folder: a sandy floor at 6 m with darker stripes, the vehicle at 3 m depth heading
// north at 0.5 m/s for 2 s, and two small cameras.
std::string makeRun(const std::string& name, bool with_trajectory = true) {
  const std::string run = test::freshFolder(name);
  Mesh floor;
  for (int i = 0; i < 10; ++i) {
    // The scenario's mesh is z-up: z = -6 lands at 6 m depth (NED).
    Mesh stripe = test::quadMesh(
        Eigen::Vector3f(-9 + 2 * i, 0, -6), Eigen::Vector3f::UnitX(), Eigen::Vector3f::UnitY(), 1,
        10, i % 2 ? Eigen::Vector3f(0.8f, 0.7f, 0.5f) : Eigen::Vector3f(0.4f, 0.35f, 0.3f));
    if (floor.vertices.empty()) {
      floor = stripe;
    } else {
      appendMesh(floor, stripe);
    }
  }
  saveMesh(floor, run + "/floor.ply");
  std::ofstream(run + "/scenario.yaml")
      << "name: test_run\n"
         "world: {mesh: floor.ply, up_axis: z, origin: [0, 0, 0]}\n"
         "water: {visibility: 12}\n"
         "vehicle: {start: {position: [0, 0, 3]}}\n"
         "cameras:\n"
         "  - {id: left, width: 160, height: 120, frame_rate: 5}\n"
         "  - {id: forward, width: 160, height: 120, frame_rate: 4, synchronized: true}\n";
  if (with_trajectory) {
    fs::create_directories(run + "/ground_truth");
    std::ofstream tum(run + "/ground_truth/trajectory.tum");
    tum << "# t x y z qx qy qz qw\n";
    for (int k = 0; k <= 20; ++k) {
      tum << 0.1 * k << " " << 0.05 * k << " 0 3 0 0 0 1\n";
    }
  }
  return run;
}

struct ImageEntry {
  int64_t id;
  Eigen::Quaterniond q;
  Eigen::Vector3d t;
  int camera;
  std::string name;
};

std::vector<ImageEntry> readImages(const std::string& path) {
  std::ifstream in(path);
  std::vector<ImageEntry> entries;
  std::string line;
  bool expect_points = false;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] == '#') continue;
    if (expect_points) {
      EXPECT_TRUE(line.empty()) << "POINTS2D line should be empty";
      expect_points = false;
      continue;
    }
    std::istringstream fields(line);
    ImageEntry e;
    double qw, qx, qy, qz;
    fields >> e.id >> qw >> qx >> qy >> qz >> e.t.x() >> e.t.y() >> e.t.z() >> e.camera >> e.name;
    e.q = Eigen::Quaterniond(qw, qx, qy, qz);
    entries.push_back(e);
    expect_points = true;
  }
  return entries;
}

TEST(RenderRun, WritesVideosSidecarsAndGroundTruth) {
  const std::string run = makeRun("run_ok");
  RenderRunOptions options;
  options.cameras = {"left"};
  options.max_frames = 4;
  options.threads = 2;
  RenderRunReport report = renderRun(run, options);
  ASSERT_EQ(report.videos.size(), 1u);
  EXPECT_EQ(report.videos[0].frames, 4);
  // A second call renders the other camera; cameras.txt keeps both.
  options.cameras = {"forward"};
  options.max_frames = 0;
  options.threads = 1;
  report = renderRun(run, options);
  EXPECT_EQ(report.videos[0].frames, 9);  // 4 fps, synchronised, over [0, 2] s

  const Scenario scenario = loadScenario(run + "/scenario.yaml");
  const CameraRig rig = CameraRig::fromScenario(scenario);
  const Trajectory trajectory = Trajectory::load(run + "/ground_truth/trajectory.tum");
  for (const auto& [id, camera_id, frames] :
       {std::tuple{std::string("left"), 1, 4}, std::tuple{std::string("forward"), 2, 9}}) {
    const std::string video = cameraVideoPath(run, id);
    EXPECT_EQ(video, run + "/vehicle/recordings/" + id + "/" + id + "_0001.mp4");
    cv::VideoCapture capture(video);
    ASSERT_TRUE(capture.isOpened()) << video;
    int read = 0;
    cv::Mat frame, last;
    while (capture.read(frame)) ++read, last = frame.clone();
    EXPECT_EQ(read, frames) << id;
    ASSERT_EQ(last.size(), cv::Size(160, 120));
    // Underwater colour cast: green above red.
    const cv::Scalar mean = cv::mean(last);
    EXPECT_GT(mean[1], mean[2] + 10) << id;

    const CameraOptions& camera = rig.camera(id);
    const std::vector<FrameStamp> stamps = readFrameSidecar(VideoRecorder::sidecarPath(video));
    ASSERT_EQ(stamps.size(), static_cast<size_t>(frames));
    const std::vector<ImageEntry> images = readImages(run + "/ground_truth/images_" + id + ".txt");
    ASSERT_EQ(images.size(), static_cast<size_t>(frames));
    for (size_t k = 0; k < stamps.size(); ++k) {
      EXPECT_NEAR(stamps[k].camera_time, camera.cameraTime(0.0) + k / camera.frame_rate, 2e-6);
      EXPECT_NEAR(stamps[k].sim_time, camera.simTime(stamps[k].camera_time), 2e-6);
      EXPECT_EQ(images[k].name, id + "_0001.mp4#" + std::to_string(k));
      EXPECT_EQ(images[k].camera, camera_id);
      const Eigen::Isometry3d truth =
          (trajectory.poseAt(stamps[k].sim_time) * camera.cameraToBody()).inverse();
      EXPECT_LT(images[k].q.angularDistance(Eigen::Quaterniond(truth.linear())), 1e-6);
      EXPECT_LT((images[k].t - truth.translation()).norm(), 1e-5);
    }
  }
  std::ifstream cameras(run + "/ground_truth/cameras.txt");
  std::string line;
  std::vector<std::string> data;
  while (std::getline(cameras, line)) {
    if (!line.empty() && line[0] != '#') data.push_back(line);
  }
  ASSERT_EQ(data.size(), 2u);
  const CameraIntrinsics k = rig.camera("left").intrinsics();
  std::istringstream fields(data[0]);
  int id, width, height;
  std::string model;
  double fx, fy, cx, cy;
  fields >> id >> model >> width >> height >> fx >> fy >> cx >> cy;
  EXPECT_EQ(id, 1);
  EXPECT_EQ(model, "OPENCV");
  EXPECT_EQ(width, 160);
  EXPECT_NEAR(fx, k.fx, 1e-6);
  EXPECT_NEAR(cx, k.cx + 0.5, 1e-9);  // COLMAP's pixel convention
  // No temporary file is left anywhere.
  for (const auto& entry : fs::recursive_directory_iterator(run)) {
    EXPECT_EQ(entry.path().string().find("incomplete"), std::string::npos) << entry.path();
  }
}

TEST(RenderRun, ErrorsNameTheFile) {
  auto message = [](const std::string& run, RenderRunOptions options = {}) -> std::string {
    try {
      renderRun(run, options);
    } catch (const std::exception& e) {
      return e.what();
    }
    return "no error";
  };
  const std::string no_trajectory = makeRun("run_no_trajectory", false);
  std::string m = message(no_trajectory);
  EXPECT_NE(m.find("ground_truth/trajectory.tum"), std::string::npos) << m;

  const std::string bad_scenario = makeRun("run_bad_scenario");
  std::ofstream(bad_scenario + "/scenario.yaml", std::ios::app) << "watr: {}\n";
  m = message(bad_scenario);
  EXPECT_NE(m.find("scenario.yaml"), std::string::npos) << m;
  EXPECT_NE(m.find("watr"), std::string::npos) << m;

  const std::string bad_line = makeRun("run_bad_line");
  std::ofstream(bad_line + "/ground_truth/trajectory.tum", std::ios::app) << "3.0 1 2\n";
  m = message(bad_line);
  EXPECT_NE(m.find("trajectory.tum:23:"), std::string::npos) << m;

  RenderRunOptions unknown;
  unknown.cameras = {"aft"};
  EXPECT_THROW(renderRun(makeRun("run_unknown_camera"), unknown), std::invalid_argument);
  m = message("/nonexistent/run");
  EXPECT_NE(m.find("/nonexistent/run"), std::string::npos) << m;
}

}  // namespace
}  // namespace auv::sim
