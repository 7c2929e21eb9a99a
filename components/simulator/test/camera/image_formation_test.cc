// Underwater image formation against its closed form: Beer-Lambert attenuation of the direct
// signal per channel, backscatter saturating to the veiling light, daylight attenuated by
// depth, artificial lights, and the sensor (vignetting, sRGB, noise, motion blur).
#include <gtest/gtest.h>

#include <cmath>

#include "auv/sim/camera/image_formation.h"
#include "auv/sim/camera/renderer.h"
#include "auv/sim/camera/trajectory.h"
#include "camera_test_scenes.h"

namespace auv::sim {
namespace {

WaterOptics testWater() {
  WaterOptics water;
  water.attenuation = {0.37, 0.10, 0.12};
  water.backscatter = {0.30, 0.09, 0.10};
  water.veiling_light = {0.03, 0.22, 0.26};
  return water;
}

// Daylight straight from above; surfaces facing sideways get only the ambient part.
IlluminationOptions overheadSun() {
  IlluminationOptions sun;
  sun.surface_irradiance = {1.0, 1.0, 1.0};
  sun.sun_zenith_deg = 0.0;
  sun.ambient = 0.4;
  sun.diffuse_attenuation_ratio = 0.5;
  sun.veiling_gain_up = 0.3;
  return sun;
}

// Mean linear colour of the central 4x4 pixels.
Eigen::Vector3d centreMean(const cv::Mat& radiance) {
  const cv::Scalar mean =
      cv::mean(radiance(cv::Rect(radiance.cols / 2 - 2, radiance.rows / 2 - 2, 4, 4)));
  return {mean[0], mean[1], mean[2]};
}

constexpr double kCameraDepth = 5.0;
constexpr float kAlbedo = 0.5f;

// A grey wall `distance` m north of a camera at 5 m depth looking north, lights off.
Eigen::Vector3d renderGreyWall(double distance, cv::Mat* developed) {
  const Mesh wall =
      test::quadMesh(Eigen::Vector3f(distance, 0, kCameraDepth), Eigen::Vector3f::UnitY(),
                     Eigen::Vector3f::UnitZ(), 20, 20, test::greySrgb(kAlbedo));
  const RayCaster caster(wall);
  const CameraModel camera(test::idealCamera());
  const Eigen::Isometry3d pose = test::lookAlong({0, 0, kCameraDepth}, Eigen::Vector3d::UnitX());
  const ImageFormation formation(testWater(), overheadSun());
  const cv::Mat radiance = renderRadiance(camera, {pose}, formation, caster, 2);
  if (developed) *developed = developImage(radiance, camera.cosOffAxis(), camera.options(), 0);
  return centreMean(radiance);
}

TEST(ImageFormation, BeerLambertGreyPatchMatchesTheModelAtEveryDistance) {
  const WaterOptics water = testWater();
  const IlluminationOptions sun = overheadSun();
  const std::vector<double> distances = {1, 2, 4, 6, 8};
  std::vector<Eigen::Vector3d> direct;  // the measured direct signal, backscatter removed
  for (double d : distances) {
    cv::Mat developed;
    const Eigen::Vector3d measured = renderGreyWall(d, &developed);
    for (int c = 0; c < 3; ++c) {
      // The wall faces the camera, so the overhead sun reaches it only as ambient light.
      const double irradiance =
          std::exp(-sun.diffuse_attenuation_ratio * water.attenuation[c] * kCameraDepth) *
          sun.ambient;
      const double backscatter = water.veiling_light[c] * (1 - std::exp(-water.backscatter[c] * d));
      const double expected =
          kAlbedo * irradiance * std::exp(-water.attenuation[c] * d) + backscatter;
      EXPECT_NEAR(measured[c], expected, 0.02 * expected) << "channel " << c << " at " << d << " m";
      // The recorded 8-bit frame decodes to the same within a quantisation step.
      const cv::Scalar bgr = cv::mean(developed(cv::Rect(78, 58, 4, 4)));
      const double decoded = srgbToLinear(static_cast<float>(bgr[2 - c] / 255.0));
      EXPECT_NEAR(decoded, expected, 0.02 * expected + 0.004) << "8-bit, channel " << c;
    }
    Eigen::Vector3d signal;
    for (int c = 0; c < 3; ++c) {
      signal[c] = measured[c] - water.veiling_light[c] * (1 - std::exp(-water.backscatter[c] * d));
    }
    direct.push_back(signal);
  }
  // Per channel, ln(direct) falls with distance at the attenuation coefficient (LSQ slope).
  for (int c = 0; c < 3; ++c) {
    double mean_d = 0, mean_l = 0;
    for (size_t i = 0; i < distances.size(); ++i) {
      mean_d += distances[i] / distances.size();
      mean_l += std::log(direct[i][c]) / distances.size();
    }
    double num = 0, den = 0;
    for (size_t i = 0; i < distances.size(); ++i) {
      num += (distances[i] - mean_d) * (std::log(direct[i][c]) - mean_l);
      den += (distances[i] - mean_d) * (distances[i] - mean_d);
    }
    EXPECT_NEAR(-num / den, water.attenuation[c], 0.02 * water.attenuation[c]) << "channel " << c;
  }
  // Red is lost first.
  const Eigen::Vector3d kept = direct.back().cwiseQuotient(direct.front());
  EXPECT_LT(kept[0], kept[1]);
  EXPECT_LT(kept[0], kept[2]);
  EXPECT_LT(kept[0], 0.1);
}

TEST(ImageFormation, RayToNothingSeesTheVeilingLight) {
  const WaterOptics water = testWater();
  const IlluminationOptions sun = overheadSun();
  // Something must exist for Embree; put it behind the camera.
  const Mesh behind = test::quadMesh({-50, 0, 5}, Eigen::Vector3f::UnitY(),
                                     Eigen::Vector3f::UnitZ(), 1, 1, Eigen::Vector3f::Ones());
  const RayCaster caster(behind);
  const CameraModel camera(test::idealCamera());
  const ImageFormation formation(water, sun);
  const cv::Mat level =
      renderRadiance(camera, {test::lookAlong({0, 0, kCameraDepth}, Eigen::Vector3d::UnitX())},
                     formation, caster, 1);
  const Eigen::Vector3d centre = centreMean(level);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(centre[c], water.veiling_light[c], 1e-3);
  // Blue-green, and brighter looking up towards the surface than looking down.
  EXPECT_GT(centre[1], 5 * centre[0]);
  const Eigen::Vector3f up = formation.waterRadiance({0, 0, -1});
  const Eigen::Vector3f down = formation.waterRadiance({0, 0, 1});
  EXPECT_NEAR(up[1], water.veiling_light[1] * 1.3, 1e-6);
  EXPECT_NEAR(down[1], water.veiling_light[1], 1e-6);
}

TEST(ImageFormation, BlackSurfaceShowsOnlyBackscatter) {
  const WaterOptics water = testWater();
  const ImageFormation formation(water, overheadSun());
  for (double d : {0.5, 3.0, 30.0}) {
    const Eigen::Vector3f radiance =
        formation.surfaceRadiance({1, 0, 0}, static_cast<float>(d), {static_cast<float>(d), 0, 5},
                                  {-1, 0, 0}, Eigen::Vector3f::Zero());
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(radiance[c], water.veiling_light[c] * (1 - std::exp(-water.backscatter[c] * d)),
                  1e-6);
    }
  }
}

TEST(ImageFormation, DaylightOnTheSeabedFallsWithDepth) {
  // A camera 2 m above a grey floor; the floor at 5 m and at 15 m depth.
  const WaterOptics water = testWater();
  const IlluminationOptions sun = overheadSun();
  auto floorSignal = [&](double depth) {
    const Mesh floor = test::quadMesh(Eigen::Vector3f(0, 0, depth), Eigen::Vector3f::UnitX(),
                                      Eigen::Vector3f::UnitY(), 30, 30, test::greySrgb(kAlbedo));
    const RayCaster caster(floor);
    const CameraModel camera(test::idealCamera());
    const ImageFormation formation(water, sun);
    const cv::Mat radiance = renderRadiance(
        camera,
        {test::lookAlong({0, 0, depth - 2}, Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX())},
        formation, caster, 1);
    Eigen::Vector3d m = centreMean(radiance);
    for (int c = 0; c < 3; ++c)
      m[c] -= water.veiling_light[c] * (1 - std::exp(-water.backscatter[c] * 2));
    return m;
  };
  const Eigen::Vector3d shallow = floorSignal(5), deep = floorSignal(15);
  for (int c = 0; c < 3; ++c) {
    // Facing the sun: full daylight exp(-K * depth), seen through 2 m of water.
    const double K = sun.diffuse_attenuation_ratio * water.attenuation[c];
    EXPECT_NEAR(shallow[c], kAlbedo * std::exp(-K * 5 - water.attenuation[c] * 2),
                0.02 * shallow[c]);
    EXPECT_NEAR(deep[c] / shallow[c], std::exp(-K * 10), 0.03 * deep[c] / shallow[c]);
  }
}

TEST(ImageFormation, ArtificialLightFollowsInverseSquareAndTwoWayAttenuation) {
  WaterOptics water = testWater();
  IlluminationOptions night = overheadSun();
  night.surface_irradiance.setZero();
  SpotLight light;
  light.position = {0, 0, 5};
  light.direction = {1, 0, 0};
  light.intensity = 4.0f;
  light.beam_deg = 60.0f;
  const ImageFormation formation(water, night, {light});
  for (double d : {1.0, 2.0, 4.0}) {
    const Eigen::Vector3f radiance =
        formation.surfaceRadiance({1, 0, 0}, static_cast<float>(d), {static_cast<float>(d), 0, 5},
                                  {-1, 0, 0}, Eigen::Vector3f::Constant(kAlbedo));
    for (int c = 0; c < 3; ++c) {
      const double expected = kAlbedo * 4.0 * std::exp(-2 * water.attenuation[c] * d) / (d * d) +
                              water.veiling_light[c] * (1 - std::exp(-water.backscatter[c] * d));
      EXPECT_NEAR(radiance[c], expected, 1e-5 + 1e-5 * expected);
    }
  }
  // Outside the beam (45 deg off a 60 deg cone, beyond its soft edge): no light.
  const Eigen::Vector3f outside =
      formation.irradiance({2, 2, 5}, Eigen::Vector3f(-1, -1, 0).normalized());
  EXPECT_EQ(outside.norm(), 0.0f);
}

TEST(ImageFormation, SensorVignettingAndEncoding) {
  CameraOptions options = test::idealCamera();
  options.vignetting = 1.0;
  const CameraModel camera(options);
  const cv::Mat grey(camera.height(), camera.width(), CV_32FC3, cv::Scalar::all(0.4));
  const cv::Mat frame = developImage(grey, camera.cosOffAxis(), options, 0);
  // Centre: almost on axis; corner: cos^4 of its off-axis angle.
  const float corner_cos = camera.cosOffAxis().at<float>(0, 0);
  const double corner_expected = 255 * linearToSrgb(0.4f * std::pow(corner_cos, 4.0f));
  EXPECT_NEAR(frame.at<cv::Vec3b>(0, 0)[1], corner_expected, 0.6);
  EXPECT_NEAR(frame.at<cv::Vec3b>(60, 80)[1], 255 * linearToSrgb(0.4f), 1.0);
  EXPECT_LT(corner_cos, 0.75f);  // a wide lens: the corner is clearly darker
  // Exposure gain, then clipping at full scale.
  options.vignetting = 0;
  options.exposure = 4.0;
  const cv::Mat bright = developImage(grey, camera.cosOffAxis(), options, 0);
  EXPECT_EQ(bright.at<cv::Vec3b>(60, 80)[0], 255);
}

TEST(ImageFormation, SensorNoiseIsSeededWithTheConfiguredSigma) {
  CameraOptions options = test::idealCamera();
  options.noise_sigma = 0.02;
  const CameraModel camera(options);
  const cv::Mat grey(camera.height(), camera.width(), CV_32FC3, cv::Scalar::all(0.2));
  const cv::Mat a = developImage(grey, camera.cosOffAxis(), options, frameSeed(7, 3));
  const cv::Mat b = developImage(grey, camera.cosOffAxis(), options, frameSeed(7, 3));
  const cv::Mat c = developImage(grey, camera.cosOffAxis(), options, frameSeed(7, 4));
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(a, c, cv::NORM_INF), 0.0);
  cv::Scalar mean, stddev;
  cv::meanStdDev(a.reshape(1), mean, stddev);
  EXPECT_NEAR(stddev[0], 0.02 * 255, 0.1 * 0.02 * 255);
  EXPECT_NEAR(mean[0], 255 * linearToSrgb(0.2f), 0.5);
}

TEST(ImageFormation, AutoExposureKeepsWaterAndDaylitWhiteLevelsAtAnyDepth) {
  // A white surface facing up right at the camera's depth reads full scale in green and the
  // open water reads the veiling light, at 2 m as at 20 m; red fades with depth.
  const WaterOptics water = testWater();
  const IlluminationOptions sun = overheadSun();
  const CameraOptions camera = test::idealCamera();
  Eigen::Vector3f previous_white = Eigen::Vector3f::Constant(2.0f);
  for (double depth : {2.0, 20.0}) {
    const ImageFormation formation =
        cameraImageFormation(camera, water, sun, {}, Eigen::Vector3d(0, 0, depth));
    EXPECT_NEAR(formation.exposureReference(),
                std::exp(-sun.diffuse_attenuation_ratio * water.attenuation[1] * depth), 1e-9);
    const Eigen::Vector3f white = formation.surfaceRadiance(
        {0, 0, 1}, 0.0f, {0, 0, static_cast<float>(depth)}, {0, 0, -1}, Eigen::Vector3f::Ones());
    EXPECT_NEAR(white[1], 1.0f, 1e-5);
    EXPECT_NEAR(white[0],
                std::exp(-sun.diffuse_attenuation_ratio *
                         (water.attenuation[0] - water.attenuation[1]) * depth),
                1e-5);
    const Eigen::Vector3f open_water = formation.waterRadiance({1, 0, 0});
    EXPECT_NEAR(open_water[1], water.veiling_light[1], 1e-6);
    EXPECT_LT(white[0], 0.5f * previous_white[0]);  // red fades as the camera dives
    previous_white = white;
  }
  // Without auto exposure the same surface darkens with depth.
  CameraOptions manual = camera;
  manual.auto_exposure = false;
  EXPECT_EQ(
      cameraImageFormation(manual, water, sun, {}, Eigen::Vector3d(0, 0, 20)).exposureReference(),
      1.0);
}

TEST(ImageFormation, MotionBlurSpreadsAMovingEdgeOverItsTravel) {
  // A white half-plane 2 m ahead; the camera slides sideways during the exposure so that the
  // edge travels ~8 px across the image.
  const Mesh wall = test::quadMesh({2, 5, 5}, Eigen::Vector3f::UnitY(), Eigen::Vector3f::UnitZ(), 5,
                                   5, Eigen::Vector3f::Ones());
  const RayCaster caster(wall);
  CameraOptions options = test::idealCamera();
  options.position = {0, 0, 0};
  options.pitch_deg = options.roll_deg = options.yaw_deg = 0;
  options.exposure_time = 0.02;
  options.max_blur_samples = 16;
  WaterOptics clear;
  clear.attenuation.setZero();
  clear.backscatter.setZero();
  clear.veiling_light.setZero();
  IlluminationOptions flat;
  flat.ambient = 1.0;
  const ImageFormation formation(clear, flat);
  const CameraModel camera(options);
  const double travel_px = 8.0;
  const double shift_m = travel_px * 2.0 / camera.intrinsics().fx;
  const double speed = shift_m / options.exposure_time;  // m/s east
  TimedPose start, end;
  start.time = 0, end.time = 1;
  start.position = {0, -0.5 * speed, 5};  // at t = 0.5 s the camera is level with the edge
  end.position = {0, 0.5 * speed, 5};
  const Trajectory trajectory({start, end});
  auto intermediatePixels = [&](const CameraModel& model) {
    const std::vector<Eigen::Isometry3d> poses = exposurePoses(trajectory, model, 0.5);
    const cv::Mat radiance = renderRadiance(model, poses, formation, caster, 2);
    int count = 0;
    for (int col = 0; col < radiance.cols; ++col) {
      const float v = radiance.at<cv::Vec3f>(radiance.rows / 2, col)[1];
      if (v > 0.05f && v < 0.95f) ++count;
    }
    return std::make_pair(count, poses.size());
  };
  const auto [blurred, samples] = intermediatePixels(camera);
  EXPECT_GE(samples, 9u);
  EXPECT_GE(blurred, static_cast<int>(travel_px) - 2);
  EXPECT_LE(blurred, static_cast<int>(travel_px) + 2);
  options.exposure_time = 0;
  const auto [sharp, one] = intermediatePixels(CameraModel(options));
  EXPECT_EQ(one, 1u);
  EXPECT_LE(sharp, 1);
}

}  // namespace
}  // namespace auv::sim
