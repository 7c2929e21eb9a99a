// The camera model: intrinsics from the options, the default rig's mounting, the clock, the
// strict YAML reading, and per-pixel rays that agree with OpenCV's projection.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <opencv2/calib3d.hpp>

#include "auv/sim/camera/camera_model.h"
#include "auv/sim/camera/camera_rig.h"
#include "auv/sim/camera/image_formation.h"
#include "auv/sim/camera/renderer.h"
#include "camera_test_scenes.h"

namespace auv::sim {
namespace {

constexpr double kDeg = M_PI / 180.0;

YamlSection yamlOf(const std::string& text, const std::string& name) {
  const std::string path = test::freshFolder(name) + "/scenario.yaml";
  std::ofstream(path) << text;
  return loadYamlFile(path);
}

TEST(CameraModel, DefaultRigMatchesThePaper) {
  const CameraRig rig = CameraRig::defaults();
  ASSERT_EQ(rig.ids(), (std::vector<std::string>{"left", "right", "forward"}));
  const auto axis = [&](const std::string& id) {
    return Eigen::Vector3d(rig.camera(id).cameraToBody().linear().col(2));
  };
  // Down-looking, tilted 20 deg to port (left) and starboard (right); forward 40 deg down.
  EXPECT_TRUE(
      axis("left").isApprox(Eigen::Vector3d(0, -std::sin(20 * kDeg), std::cos(20 * kDeg)), 1e-9));
  EXPECT_TRUE(
      axis("right").isApprox(Eigen::Vector3d(0, std::sin(20 * kDeg), std::cos(20 * kDeg)), 1e-9));
  EXPECT_TRUE(
      axis("forward").isApprox(Eigen::Vector3d(std::cos(40 * kDeg), 0, std::sin(40 * kDeg)), 1e-9));
  // The down cameras' image top points forward.
  const Eigen::Vector3d image_down = rig.camera("left").cameraToBody().linear().col(1);
  EXPECT_NEAR(image_down.x(), -1.0, 1e-9);
  // Unsynchronised by default: every camera has its own clock.
  EXPECT_NE(rig.camera("left").clock_offset, rig.camera("right").clock_offset);
  EXPECT_THROW(rig.camera("aft"), std::invalid_argument);
}

TEST(CameraModel, FocalLengthSpansTheFieldOfViewWithDistortion) {
  CameraOptions options = test::idealCamera(960, 720);
  options.hfov_deg = 85.0;
  const CameraModel camera(options);
  // A point 42.5 deg off-axis on the middle row lands on the image's edge (pixel -0.5 / w-0.5).
  const double t = std::tan(42.5 * kDeg);
  const auto right = camera.project({t, 0, 1});
  const auto left = camera.project({-t, 0, 1});
  ASSERT_TRUE(right && left);
  EXPECT_NEAR(right->x(), 959.5, 1e-6);
  EXPECT_NEAR(left->x(), -0.5, 1e-6);
  EXPECT_NEAR(right->y(), 359.5, 1e-9);
  // Pin-cushion (k1 > 0): the pinhole focal length is shorter than without distortion.
  EXPECT_LT(camera.intrinsics().fx, 480.0 / t);
}

TEST(CameraModel, RaysReprojectOntoTheirPixelsLikeCvProjectPoints) {
  CameraOptions options = test::idealCamera(320, 240);
  options.distortion = {0.12, 0.03, 0.001, -0.002, 0.005};
  options.cx = 165.0;
  options.cy = 117.0;
  const CameraModel camera(options);
  std::vector<cv::Point3d> points;
  std::vector<cv::Point2d> pixels;
  for (int row : {0, 1, 60, 119, 200, 239}) {
    for (int col : {0, 5, 160, 250, 319}) {
      const Eigen::Vector3f& ray = camera.rays()[static_cast<size_t>(row) * 320 + col];
      EXPECT_NEAR(ray.norm(), 1.0f, 1e-6f);
      points.emplace_back(2.5 * ray.x(), 2.5 * ray.y(), 2.5 * ray.z());
      pixels.emplace_back(col, row);
    }
  }
  std::vector<cv::Point2d> projected;
  cv::projectPoints(points, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0),
                    cv::Mat(camera.intrinsics().cameraMatrix()),
                    camera.intrinsics().distortionCoefficients(), projected);
  for (size_t i = 0; i < points.size(); ++i) {
    EXPECT_NEAR(projected[i].x, pixels[i].x, 2e-3) << "pixel " << pixels[i];
    EXPECT_NEAR(projected[i].y, pixels[i].y, 2e-3) << "pixel " << pixels[i];
    const auto ours = camera.project({points[i].x, points[i].y, points[i].z});
    ASSERT_TRUE(ours);
    EXPECT_NEAR(ours->x(), projected[i].x, 1e-9);
    EXPECT_NEAR(ours->y(), projected[i].y, 1e-9);
  }
  EXPECT_FALSE(camera.project({0, 0, -1}));
}

TEST(CameraModel, RenderedBrightSpotLandsWhereCvProjectPointsSays) {
  // A small white square far off-axis, seen through a strongly distorting lens in clear, dark
  // water: its brightness centroid must sit at the distorted projection of its centre.
  CameraOptions options = test::idealCamera(320, 240);
  options.distortion = {0.25, 0.05, 0, 0, 0};
  const CameraModel camera(options, 1.0, 4);
  const Eigen::Isometry3d camera_to_world = test::lookAlong({0, 0, 5}, Eigen::Vector3d::UnitX());
  const Eigen::Vector3d centre_camera(0.7 * 3.0, 0.45 * 3.0, 3.0);
  const Eigen::Vector3d centre_world = camera_to_world * centre_camera;
  const Eigen::Vector3f towards_camera =
      (camera_to_world.translation() - centre_world).normalized().cast<float>();
  const Eigen::Vector3f u = towards_camera.cross(Eigen::Vector3f::UnitZ()).normalized();
  const Eigen::Vector3f v = towards_camera.cross(u);
  const Mesh mesh =
      test::quadMesh(centre_world.cast<float>(), u, v, 0.06f, 0.06f, Eigen::Vector3f::Ones());
  const RayCaster caster(mesh);
  WaterOptics clear;
  clear.attenuation.setZero();
  clear.backscatter.setZero();
  clear.veiling_light.setZero();
  IlluminationOptions flat;
  flat.ambient = 1.0;
  const cv::Mat radiance =
      renderRadiance(camera, {camera_to_world}, ImageFormation(clear, flat), caster, 2);
  double sum = 0, sum_x = 0, sum_y = 0;
  for (int row = 0; row < radiance.rows; ++row) {
    for (int col = 0; col < radiance.cols; ++col) {
      const double w = radiance.at<cv::Vec3f>(row, col)[1];
      sum += w, sum_x += w * col, sum_y += w * row;
    }
  }
  ASSERT_GT(sum, 4.0);  // several pixels' worth of white
  std::vector<cv::Point2d> expected;
  cv::projectPoints(
      std::vector<cv::Point3d>{{centre_camera.x(), centre_camera.y(), centre_camera.z()}},
      cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cv::Mat(camera.intrinsics().cameraMatrix()),
      camera.intrinsics().distortionCoefficients(), expected);
  EXPECT_NEAR(sum_x / sum, expected[0].x, 0.2);
  EXPECT_NEAR(sum_y / sum, expected[0].y, 0.2);
  // The test can tell: without the distortion the spot would be far away.
  const double pinhole_x = camera.intrinsics().fx * 0.7 + camera.intrinsics().cx;
  EXPECT_GT(std::abs(pinhole_x - expected[0].x), 10.0);
}

TEST(CameraModel, ScaledIntrinsicsKeepTheLens) {
  CameraOptions options = test::idealCamera(2704, 2028);
  const CameraIntrinsics full = options.intrinsics();
  const CameraIntrinsics half = options.intrinsics(0.5);
  EXPECT_EQ(half.width, 1352);
  EXPECT_EQ(half.height, 1014);
  EXPECT_NEAR(half.fx, 0.5 * full.fx, 1e-9);
  EXPECT_NEAR(half.cx, 0.5 * (half.width - 1), 1e-9);
  EXPECT_EQ(half.distortion, full.distortion);
  // H.264 needs even sizes.
  EXPECT_EQ(options.intrinsics(0.3).width % 2, 0);
  EXPECT_EQ(options.intrinsics(0.3).height % 2, 0);
}

TEST(CameraModel, FullGoProResolutionWorks) {
  const CameraModel camera(test::idealCamera(2704, 2028));
  ASSERT_EQ(camera.rays().size(), size_t{2704} * 2028);
  // The corner ray reprojects onto the corner pixel.
  const Eigen::Vector3f corner = camera.rays().back();
  const auto pixel = camera.project(corner.cast<double>());
  ASSERT_TRUE(pixel);
  EXPECT_NEAR(pixel->x(), 2703, 1e-2);
  EXPECT_NEAR(pixel->y(), 2027, 1e-2);
}

TEST(CameraModel, ClockMapsSimulationTimeToCameraTime) {
  CameraOptions camera = CameraOptions::defaults("left");
  camera.clock_offset = 12.5;
  camera.clock_drift_ppm = 200;
  EXPECT_NEAR(camera.cameraTime(100.0), 12.5 + 100.0 * (1 + 200e-6), 1e-12);
  EXPECT_NEAR(camera.simTime(camera.cameraTime(37.25)), 37.25, 1e-12);
  camera.synchronized = true;
  EXPECT_EQ(camera.cameraTime(100.0), 100.0);
}

TEST(CameraModel, YamlStartsFromTheDefaultCameraOfThatId) {
  const YamlSection root = yamlOf(
      "cameras:\n"
      "  - {id: left, width: 640, height: 480, frame_rate: 30}\n"
      "  - {id: aft, fx: 400, distortion: [0.1, 0, 0, 0], pitch_deg: 0, yaw_deg: 180,\n"
      "     synchronized: true, lights: true, light_intensity: 5}\n",
      "yaml_ok");
  const CameraRig rig = CameraRig::fromYaml(root);
  ASSERT_EQ(rig.ids(), (std::vector<std::string>{"left", "aft"}));
  const CameraOptions& left = rig.camera("left");
  EXPECT_EQ(left.width, 640);
  EXPECT_EQ(left.frame_rate, 30);
  EXPECT_EQ(left.pitch_deg, -90);  // kept from the default left camera
  EXPECT_EQ(left.roll_deg, 20);
  const CameraOptions& aft = rig.camera("aft");
  EXPECT_EQ(aft.intrinsics().fx, 400);
  EXPECT_EQ(aft.intrinsics().fy, 400);
  EXPECT_EQ(aft.distortion[0], 0.1);
  EXPECT_TRUE(aft.synchronized);
  EXPECT_NEAR(aft.cameraToBody().linear().col(2).x(), -1.0, 1e-9);  // looking aft
  const auto lights = rig.lightsInWorld(Eigen::Isometry3d::Identity());
  ASSERT_EQ(lights.size(), 1u);
  EXPECT_EQ(lights[0].intensity, 5.0f);
  EXPECT_NEAR(lights[0].direction.x(), -1.0f, 1e-6f);
}

TEST(CameraModel, YamlErrorsNameTheFileAndField) {
  auto message = [](const std::string& text, const std::string& name) -> std::string {
    try {
      CameraRig::fromYaml(yamlOf(text, name));
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "no error";
  };
  std::string m = message("cameras:\n  - {id: left, widht: 640}\n", "typo");
  EXPECT_NE(m.find("scenario.yaml"), std::string::npos) << m;
  EXPECT_NE(m.find("cameras[0].widht"), std::string::npos) << m;
  EXPECT_NE(m.find("did you mean 'width'"), std::string::npos) << m;
  m = message("cameras:\n  - {id: left, fx: 400, hfov_deg: 80}\n", "both");
  EXPECT_NE(m.find("either fx or hfov_deg"), std::string::npos) << m;
  m = message("cameras:\n  - {id: left, distortion: [-0.6, 0, 0, 0, 0]}\n", "fold");
  EXPECT_NE(m.find("distortion"), std::string::npos) << m;
  EXPECT_NE(m.find("folds"), std::string::npos) << m;
  m = message("cameras:\n  - {id: left}\n  - {id: left}\n", "twice");
  EXPECT_NE(m.find("used by two cameras"), std::string::npos) << m;
  m = message("cameras: []\n", "empty");
  EXPECT_NE(m.find("empty"), std::string::npos) << m;
  m = message("cameras:\n  - {width: 640}\n", "noid");
  EXPECT_NE(m.find("cameras[0].id"), std::string::npos) << m;
  m = message("cameras:\n  - {id: left, frame_rate: 0}\n", "rate");
  EXPECT_NE(m.find("frame_rate"), std::string::npos) << m;
}

}  // namespace
}  // namespace auv::sim
