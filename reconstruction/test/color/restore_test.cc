// Range-aware colour restoration (water_model.h, restore_stage.h): a synthetic sea floor filmed
// through water of known backscatter, attenuation and vignetting; the blind estimate restores
// it. Bad input is named and earlier outputs stay intact.
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <random>

#include <open3d/geometry/TriangleMesh.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "../texture/synthetic_scene.h"
#include "auv/recon/color/lalphabeta.h"
#include "auv/recon/color/restore_stage.h"
#include "auv/recon/color/water_model.h"
#include "auv/recon/common/option_set.h"
#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/scene/colmap_text.h"
#include "auv/recon/scene/mesh_io.h"
#include "auv/recon/texture/texture_stage.h"

namespace fs = std::filesystem;
using namespace auv::recon;
using namespace auv::recon::color;

namespace {

struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() / ("auv_recon_restore_" + std::to_string(::getpid()) + "_" +
                                        std::to_string(std::random_device{}()));
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
};

// The water the synthetic keyframes are filmed through (r, g, b; 1/unit).
WaterModel trueWater() {
  WaterModel w;
  w.backscatter_infinity = {0.03, 0.20, 0.25};
  w.backscatter_coefficient = {0.50, 0.18, 0.20};
  w.attenuation = {0.60, 0.20, 0.25};
  w.vignetting = 0.3;
  return w;
}

// Linear albedo (r, g, b) of the floor: the texture tests' colours, with dark pebbles (the
// near-black pixels Sea-thru's backscatter estimate looks for).
// With `trendless`, fine detail on one sand colour: no trend across the floor to mistake for the
// light's.
Eigen::Array3d albedo(const Eigen::Vector3d& p, bool trendless) {
  const Eigen::Vector3f bgr = synth::trueColor(p);
  Eigen::Array3d rgb;
  for (int c = 0; c < 3; ++c) {
    rgb[c] = srgbToLinear(std::clamp(bgr[2 - c], 0.0f, 255.0f) / 255.0f);
  }
  if (trendless) {
    rgb = Eigen::Array3d(0.35, 0.3, 0.2) * (1 + 0.6 * std::sin(11 * p.x()) * std::sin(9 * p.y()));
  }
  const bool pebble = std::sin(3.1 * p.x() + 0.3) * std::sin(2.7 * p.y()) > 0.9;
  return pebble ? rgb * 0.03 : rgb;
}

// The view's image of the floor without water (sRGB, BGR) and through `water`.
void render(const texture::FaceMesh& mesh, const texture::ViewGeometry& view,
            const WaterModel& water, bool trendless, cv::Mat3b& clear, cv::Mat3b& filmed,
            cv::Mat1b& floor) {
  const texture::RasterBuffers buffers = texture::rasterize(mesh.vertices, mesh.faces, view);
  const scene::Camera& c = view.camera;
  const cv::Mat1f cos4 = cos4Map(cv::Size(c.width, c.height), c.fx, c.fy, c.cx, c.cy);
  cv::Mat3f clear_linear(c.height, c.width), filmed_linear(c.height, c.width);
  floor = cv::Mat1b(c.height, c.width, uchar(0));
  const Eigen::Vector3d center = view.center();
  for (int y = 0; y < c.height; ++y) {
    for (int x = 0; x < c.width; ++x) {
      const int f = buffers.face(y, x);
      Eigen::Array3d j = Eigen::Array3d::Zero(), i = water.backscatter_infinity;
      if (f >= 0) {
        const Eigen::Vector3d w =
            texture::barycentricAt(mesh.vertices, mesh.faces[f], view, Eigen::Vector2d(x, y));
        const Eigen::Vector3d p = w(0) * mesh.vertices[mesh.faces[f](0)] +
                                  w(1) * mesh.vertices[mesh.faces[f](1)] +
                                  w(2) * mesh.vertices[mesh.faces[f](2)];
        const double z = (p - center).norm();
        floor(y, x) = 255;
        j = albedo(p, trendless);
        i = (1 - water.vignetting * (1 - cos4(y, x))) *
            (j * water.illuminant(p) * (-water.attenuation * z).exp() + water.backscatter(z));
      }
      clear_linear(y, x) = cv::Vec3f(j[2], j[1], j[0]);
      filmed_linear(y, x) = cv::Vec3f(i[2], i[1], i[0]);
    }
  }
  clear = srgbFromLinear(clear_linear);
  filmed = srgbFromLinear(filmed_linear);
}

struct Clear {
  cv::Mat3b image;  ///< without water
  cv::Mat1b floor;  ///< pixels that see the floor (the rest is open water)
};

// A survey: mesh/mesh.ply (an undulating floor), sparse/ (one PINHOLE camera, views from 1.2 to
// 3.5 units away, moved `camera_shift_x` along x, still looking at the floor's middle),
// keyframes/left/*.png filmed through trueWater(); the clear images returned.
std::map<std::string, Clear> writeSurvey(const Survey& survey, WaterModel water = trueWater(),
                                         bool trendless = false, double camera_shift_x = 0) {
  const texture::FaceMesh mesh = synth::gridMesh(
      24, 2.0, [](double x, double y) { return 0.15 * std::sin(2 * x) * std::cos(1.5 * y); });
  open3d::geometry::TriangleMesh o3d;
  o3d.vertices_ = mesh.vertices;
  o3d.triangles_ = mesh.faces;
  fs::create_directories(survey.mesh());
  scene::writeMeshPly(survey.mesh() / "mesh.ply", o3d);
  scene::Reconstruction model;
  model.cameras[1] = scene::Camera::pinhole(1, 160, 120, 100, 100, 79.5, 59.5);
  fs::create_directories(survey.keyframes() / "left");
  std::map<std::string, Clear> clear_images;
  std::vector<Eigen::Vector3d> centers{
      Eigen::Vector3d(-0.3, -0.2, 1.2), Eigen::Vector3d(0.3, 0.2, 1.6),
      Eigen::Vector3d(0.0, -0.6, 2.2),  Eigen::Vector3d(-0.5, 0.5, 2.8),
      Eigen::Vector3d(0.6, -0.3, 3.5),  Eigen::Vector3d(0.0, 0.0, 3.0)};
  for (Eigen::Vector3d& c : centers) c.x() += camera_shift_x;
  water.illuminant_origin = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& c : centers) water.illuminant_origin += c / centers.size();
  uint32_t id = 1;
  for (const Eigen::Vector3d& c : centers) {
    texture::ViewGeometry view = synth::lookAt(
        c, Eigen::Vector3d(0.1 * (c.x() - camera_shift_x), 0.1 * c.y(), 0), 160, 120, 100);
    scene::Image image;
    image.id = id;
    image.camera_id = 1;
    image.name = "left/left_0001_00000" + std::to_string(id) + ".png";
    image.setWorldToCamera(view.world_to_camera);
    model.images[id] = image;
    Clear clear;
    cv::Mat3b filmed;
    render(mesh, view, water, trendless, clear.image, filmed, clear.floor);
    EXPECT_TRUE(cv::imwrite((survey.keyframes() / image.name).string(), filmed));
    clear_images[image.name] = clear;
    ++id;
  }
  scene::writeColmapText(model, survey.sparse());
  return clear_images;
}

// PSNR over the floor's pixels.
double psnr(const Clear& clear, const cv::Mat& image) {
  cv::Mat difference;
  cv::absdiff(clear.image, image, difference);
  difference.convertTo(difference, CV_64F);
  const cv::Scalar squares = cv::mean(difference.mul(difference), clear.floor);
  const double mse = (squares[0] + squares[1] + squares[2]) / 3;
  return 10 * std::log10(255.0 * 255.0 / std::max(mse, 1e-12));
}

std::string expectStageError(const Survey& survey, const RestoreStageOptions& options) {
  try {
    runRestoreStage(survey, options);
  } catch (const StageError& e) {
    EXPECT_EQ(e.stage(), "restore");
    return e.what();
  }
  ADD_FAILURE() << "the restore stage did not fail";
  return {};
}

}  // namespace

TEST(Restore, BlindEstimateRestoresASyntheticSurvey) {
  TempDir dir;
  const Survey survey(dir.path / "survey");
  const std::map<std::string, Clear> clear = writeSurvey(survey);
  RestoreStageOptions options;
  options.water.white_balance = "none";  // the albedo is known here, no cast to balance
  options.water.illuminant = "uniform";  // and the light uniform
  const RestoreStageResult result = runRestoreStage(survey, options);
  EXPECT_EQ(result.images, 6u);

  const WaterModel truth = trueWater(), &fit = result.model;
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(fit.attenuation[c], truth.attenuation[c], 0.35 * truth.attenuation[c]) << c;
    EXPECT_NEAR(fit.backscatter(2.5)[c], truth.backscatter(2.5)[c], 0.02) << c;
    EXPECT_NEAR(fit.backscatter_infinity[c], truth.backscatter_infinity[c], 0.05) << c;
  }
  EXPECT_NEAR(fit.vignetting, truth.vignetting, 0.1);

  // Every restored keyframe is much closer to the clear-water image than the filmed one.
  for (const auto& [name, clear_image] : clear) {
    const cv::Mat filmed = cv::imread((survey.keyframes() / name).string());
    const cv::Mat restored = cv::imread((restoredFolder(survey) / name).string());
    ASSERT_FALSE(restored.empty()) << name;
    const double before = psnr(clear_image, filmed), after = psnr(clear_image, restored);
    EXPECT_GT(after, before + 8) << name << ": " << before << " -> " << after << " dB";
    EXPECT_GT(after, 25.0) << name;
  }

  // water.yaml reads back; report.json has the section.
  const WaterModel read = readWaterModel(restoredFolder(survey) / "water.yaml");
  EXPECT_NEAR(read.attenuation[0], fit.attenuation[0], 1e-6);
  EXPECT_NEAR(read.vignetting, fit.vignetting, 1e-6);
  const nlohmann::json report = readReport(survey.report());
  EXPECT_EQ(report["stages"]["restore"]["images"].get<int>(), 6);
  EXPECT_GT(report["stages"]["restore"]["attenuation_fit"]["points"].get<int>(), 100);

  // The texture stage takes restored/ by default once it exists, corrected/ when told.
  texture::TextureStageOptions texture_options;
  texture_options.texture.atlas.max_page_size = 1024;
  texture::runTextureStage(survey, texture_options);
  EXPECT_EQ(readReport(survey.report())["stages"]["texture"]["input"]["images"], "restored/");
  texture_options.images = "corrected";
  try {
    texture::runTextureStage(survey, texture_options);
    ADD_FAILURE() << "texture from the missing corrected/ did not fail";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("corrected"), std::string::npos) << e.what();
  }
}

TEST(Restore, LightFadingAcrossTheSceneIsFound) {
  TempDir dir;
  const Survey survey(dir.path / "survey");
  WaterModel water = trueWater();
  // Daylight fading along x, red fastest (as with depth below the surface).
  water.illuminant_gradient.col(0) = Eigen::Vector3d(-0.40, -0.15, -0.20);
  const std::map<std::string, Clear> clear = writeSurvey(survey, water, true);
  RestoreStageOptions options;
  options.water.white_balance = "none";
  options.water.illuminant = "uniform";
  runRestoreStage(survey, options);
  std::map<std::string, double> uniform;
  for (const auto& [name, clear_image] : clear) {
    uniform[name] = psnr(clear_image, cv::imread((restoredFolder(survey) / name).string()));
  }
  options.water.illuminant = "gradient";
  const RestoreStageResult result = runRestoreStage(survey, options);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(result.model.illuminant_gradient(c, 0), water.illuminant_gradient(c, 0), 0.08) << c;
    EXPECT_NEAR(result.model.illuminant_gradient(c, 1), 0.0, 0.08) << c;
  }
  for (const auto& [name, clear_image] : clear) {
    const double gradient = psnr(clear_image, cv::imread((restoredFolder(survey) / name).string()));
    EXPECT_GT(gradient, uniform[name] + 2) << name;
    EXPECT_GT(gradient, 22.0) << name;
  }
  EXPECT_TRUE(readWaterModel(restoredFolder(survey) / "water.yaml")
                  .illuminant_gradient.isApprox(result.model.illuminant_gradient, 1e-6));
}

// Mean linear colour (r, g, b) of the floor's pixels over the restored keyframes.
Eigen::Array3d meanRestoredColor(const Survey& survey, const std::map<std::string, Clear>& clear) {
  Eigen::Array3d sum = Eigen::Array3d::Zero();
  for (const auto& [name, c] : clear) {
    const cv::Scalar mean =
        cv::mean(linearFromSrgb(cv::imread((restoredFolder(survey) / name).string())), c.floor);
    sum += Eigen::Array3d(mean[2], mean[1], mean[0]);
  }
  return sum / clear.size();
}

TEST(Restore, GreyWorldBalancesTheRestoredColours) {
  TempDir dir;
  const Survey survey(dir.path / "survey");
  const std::map<std::string, Clear> clear = writeSurvey(survey);
  RestoreStageOptions options;
  options.water.illuminant = "uniform";
  options.water.white_balance = "none";
  runRestoreStage(survey, options);
  const Eigen::Array3d unbalanced = meanRestoredColor(survey, clear);
  options.water.white_balance = "grey_world";
  runRestoreStage(survey, options);
  const Eigen::Array3d balanced = meanRestoredColor(survey, clear);
  // The floor is not grey (blue-green on average): balanced, it is, at the same luminance.
  EXPECT_GT(unbalanced.maxCoeff() / unbalanced.minCoeff(), 1.15) << unbalanced.transpose();
  EXPECT_LT(balanced.maxCoeff() / balanced.minCoeff(), 1.08) << balanced.transpose();
  EXPECT_NEAR(luminance(balanced), luminance(unbalanced), 0.08 * luminance(unbalanced));
}

TEST(Restore, GreyWorldKeepsTheCamerasExposureWhenTheLightVaries) {
  TempDir dir;
  const Survey survey(dir.path / "survey");
  WaterModel water = trueWater();
  water.illuminant_gradient.col(0) = Eigen::Vector3d(-0.40, -0.15, -0.20);
  // The cameras stand off to one side of the floor they film: the light at their mean position
  // is not the light on the floor, and a gradient taken there would set the exposure.
  const std::map<std::string, Clear> clear = writeSurvey(survey, water, true, 0.8);
  RestoreStageOptions options;
  options.water.illuminant = "uniform";
  options.water.white_balance = "none";
  runRestoreStage(survey, options);
  const Eigen::Array3d unlit = meanRestoredColor(survey, clear);
  options.water.illuminant = "gradient";
  options.water.white_balance = "grey_world";
  const RestoreStageResult result = runRestoreStage(survey, options);
  EXPECT_LT(result.model.illuminant_gradient(0, 0), -0.2);  // the gradient was found
  const Eigen::Array3d balanced = meanRestoredColor(survey, clear);
  // Equal over the surface points the fits used (weighted by the views that see them); over the
  // floor's pixels within 13 % (measured: +10 %; the exposure taken at the cameras: -19 %).
  EXPECT_NEAR(luminance(balanced), luminance(unlit), 0.13 * luminance(unlit))
      << balanced.transpose() << " vs " << unlit.transpose();
}

TEST(Restore, BadInputIsNamedAndEarlierOutputStays) {
  TempDir dir;
  const Survey survey(dir.path / "survey");
  RestoreStageOptions options;

  // Nothing yet: the sparse model, then the mesh, named with the command that makes them.
  std::string error = expectStageError(survey, options);
  EXPECT_NE(error.find("images.txt"), std::string::npos) << error;
  writeSurvey(survey);
  fs::rename(survey.mesh(), dir.path / "mesh.moved");
  error = expectStageError(survey, options);
  EXPECT_NE(error.find("mesh.ply"), std::string::npos) << error;
  EXPECT_NE(error.find("auv recon mesh"), std::string::npos) << error;
  fs::rename(dir.path / "mesh.moved", survey.mesh());

  runRestoreStage(survey, options);
  const fs::path water = restoredFolder(survey) / "water.yaml";
  const std::string water_text = [&] {
    std::ifstream in(water);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }();
  const fs::path first = restoredFolder(survey) / "left" / "left_0001_000001.png";
  const auto first_size = fs::file_size(first);

  // A keyframe of another size than its camera: named, with the camera's size.
  const fs::path keyframe = survey.keyframes() / "left" / "left_0001_000003.png";
  cv::imwrite(keyframe.string(), cv::Mat3b(60, 80, cv::Vec3b(10, 20, 30)));
  error = expectStageError(survey, options);
  EXPECT_NE(error.find("left_0001_000003.png"), std::string::npos) << error;
  EXPECT_NE(error.find("80x60"), std::string::npos) << error;
  EXPECT_NE(error.find("160x120"), std::string::npos) << error;

  // A missing keyframe: named.
  fs::remove(keyframe);
  error = expectStageError(survey, options);
  EXPECT_NE(error.find("left_0001_000003.png"), std::string::npos) << error;

  // restored/ as the successful run left it.
  std::ifstream in(water);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), water_text);
  EXPECT_EQ(fs::file_size(first), first_size);
  EXPECT_TRUE(fs::exists(restoredFolder(survey) / "left" / "left_0001_000003.png"));

  // The texture stage asked for restored/ where there is none: named.
  texture::TextureStageOptions texture_options;
  texture_options.images = "restored";
  fs::remove_all(restoredFolder(survey));
  try {
    texture::runTextureStage(survey, texture_options);
    ADD_FAILURE() << "texture from a missing restored/ did not fail";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("water.yaml"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("auv recon restore"), std::string::npos) << e.what();
  }
}

// Water that cannot be estimated (here: no surface point seen by enough views) is not a
// failure of the run: nothing restored, the earlier restored/ goes, texture uses corrected/.
TEST(Restore, WaterThatCannotBeEstimatedLeavesTheCorrectedImagesToTexture) {
  TempDir dir;
  const Survey survey(dir.path / "survey");
  writeSurvey(survey);
  RestoreStageOptions options;
  runRestoreStage(survey, options);
  ASSERT_TRUE(fs::exists(restoredFolder(survey) / "water.yaml"));
  options.water.min_views = 100000;
  const RestoreStageResult result = runRestoreStage(survey, options);
  EXPECT_NE(result.not_restored.find("mesh.ply"), std::string::npos) << result.not_restored;
  EXPECT_EQ(result.images, 0u);
  EXPECT_FALSE(fs::exists(restoredFolder(survey)));
  const StageReport report = RestoreStage().runWith(survey, options);
  ASSERT_EQ(report.warnings.size(), 1u);
  EXPECT_NE(report.warnings[0].find("corrected/"), std::string::npos) << report.warnings[0];
}

TEST(Restore, RangeMapOfAnotherSizeIsRefused) {
  const cv::Mat3b image(120, 160, cv::Vec3b(50, 60, 70));
  const cv::Mat1f range(60, 80, 2.0f);
  try {
    restoreImage(image, range, cv::Mat(), trueWater(), WaterFitOptions{});
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("160x120"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("80x60"), std::string::npos) << e.what();
  }
  // Same sizes: restored; no range anywhere: the farthest range (none: 0) is used.
  const cv::Mat out =
      restoreImage(image, cv::Mat1f(120, 160, 2.0f), cv::Mat(), trueWater(), WaterFitOptions{});
  EXPECT_EQ(out.size(), image.size());
  EXPECT_EQ(out.type(), CV_8UC3);
}

TEST(Restore, FitsRefuseTooLittleData) {
  WaterModel model;
  std::vector<RangeSample> samples(10, RangeSample{2.0f, Eigen::Array3f(0.1f, 0.2f, 0.3f)});
  EXPECT_THROW(fitBackscatter(samples, WaterFitOptions{}, model), std::invalid_argument);
  std::vector<PointObservation> observations{{0, 1.0f, 1.0f, Eigen::Array3f(0.5f, 0.5f, 0.5f)},
                                             {0, 2.0f, 1.0f, Eigen::Array3f(0.4f, 0.4f, 0.4f)}};
  EXPECT_THROW(fitAttenuation(observations, WaterFitOptions{}, model), std::invalid_argument);
}

TEST(Restore, OptionsAreCheckedAndBound) {
  RestoreStageOptions options;
  options.water.white_balance = "purple";
  try {
    options.check();
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("white_balance"), std::string::npos) << e.what();
  }
  options = RestoreStageOptions{};
  options.blur_px = 4;
  EXPECT_THROW(options.check(), std::invalid_argument);
  options = RestoreStageOptions{};
  OptionSet set("restore");
  options.bind(set);
  ASSERT_TRUE(set.parse({"--range-bins", "12", "--no-estimate-vignetting", "--white-balance",
                         "none", "--max-points", "500"}));
  EXPECT_EQ(options.water.range_bins, 12);
  EXPECT_FALSE(options.water.estimate_vignetting);
  EXPECT_EQ(options.water.white_balance, "none");
  EXPECT_EQ(options.max_points, 500);
  EXPECT_NO_THROW(options.check());
}
