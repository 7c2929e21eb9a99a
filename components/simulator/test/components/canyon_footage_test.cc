// The acceptance check for the cameras, as a test: neighbouring frames of the canyon,
// filmed 0.8 m from the rock at cruise speed, look like underwater footage of textured rock —
// SIFT finds hundreds of matches between them — and the water's cast is blue-green.
#include <gtest/gtest.h>

#include <cstdlib>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>

#include "auv/sim/camera/camera_rig.h"
#include "auv/sim/camera/renderer.h"
#include "auv/sim/vehicle/vehicle.h"
#include "auv/sim/world/scenario.h"
#include "auv/sim/worldgen/world_generator.h"

namespace auv::sim {
namespace {

TEST(CanyonFootageTest, NeighbouringFramesShareHundredsOfSiftMatchesAndLookUnderwater) {
  WorldGenOptions options;
  options.seed = 1;
  const GeneratedWorld world = generateWorld("canyon", options);
  Mesh mesh = world.mesh;
  transformMesh(mesh, Scenario().meshToWorld());  // z-up mesh at origin 0, as its scenario
  SurfaceDetailOptions detail;                    // as the generated scenario sets it
  detail.amplitude = 0.9;
  detail.seed = static_cast<int64_t>(options.seed);
  const RayCaster caster(mesh, detail);
  const WaterOptics water = WaterOptics::fromVisibility(world.visibility);  // 4.5 m

  // Beside the canyon's east wall, 0.8 m from it (close-range inspection in 4.5 m visibility:
  // at 2 m the rock is mostly veiled), the starboard camera films the wall; 0.8 m/s at 10 fps
  // = 8 cm per frame.
  const auto& axis = world.layout.canyon_axis;
  ASSERT_GE(axis.size(), 10u);
  const Eigen::Vector3d middle = axis[axis.size() / 2];
  const Eigen::Vector3d ahead = (axis[axis.size() / 2 + 1] - middle).normalized();
  const Eigen::Vector3d starboard(-ahead.y(), ahead.x(), 0);
  const double wall = caster.cast(middle.cast<float>(), starboard.cast<float>(), 20.0f).distance;
  ASSERT_LT(wall, 10.0);
  const Eigen::Vector3d beside = middle + (wall - 0.8) * starboard;
  CameraOptions camera = CameraRig::defaults().camera("right");  // default 960 x 720
  const CameraModel model(camera);
  const auto cameraPose = [&](double along) {
    VehicleState state;
    state.position = beside + along * ahead;
    state.yaw = std::atan2(ahead.y(), ahead.x());
    return state.pose() * camera.cameraToBody();
  };
  const cv::Mat a = renderFrame(model, cameraPose(0.0), water, caster, {}, 1);
  const cv::Mat b = renderFrame(model, cameraPose(0.08), water, caster, {}, 2);
  if (const char* dir = std::getenv("AUV_TEST_IMAGE_DIR")) {  // to look at the frames
    cv::imwrite(std::string(dir) + "/canyon_frame_a.png", a);
    cv::imwrite(std::string(dir) + "/canyon_frame_b.png", b);
  }

  // COLMAP's default SIFT sensitivity (peak threshold 0.02 / 3 layers; OpenCV's default
  // contrastThreshold 0.04 is twice as strict, too strict for low-contrast underwater frames).
  cv::Ptr<cv::SIFT> sift = cv::SIFT::create(0, 3, 0.02);
  std::vector<cv::KeyPoint> ka, kb;
  cv::Mat da, db;
  sift->detectAndCompute(a, cv::noArray(), ka, da);
  sift->detectAndCompute(b, cv::noArray(), kb, db);
  ASSERT_GT(ka.size(), 100u);
  ASSERT_GT(kb.size(), 100u);
  cv::BFMatcher matcher(cv::NORM_L2);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(da, db, knn, 2);
  int good = 0;
  for (const auto& m : knn) {
    if (m.size() == 2 && m[0].distance < 0.75f * m[1].distance) ++good;  // Lowe's ratio test
  }
  EXPECT_GE(good, 200) << good << " matches, " << ka.size() << " and " << kb.size() << " keypoints";

  // Blue-green cast: blue and green dominate red.
  const cv::Scalar mean = cv::mean(a);  // B, G, R
  EXPECT_GT(mean[0], 1.5 * mean[2]);
  EXPECT_GT(mean[1], 1.5 * mean[2]);
}

}  // namespace
}  // namespace auv::sim
