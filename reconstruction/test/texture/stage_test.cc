// `auv recon texture` on a survey folder: reads mesh/, sparse/, corrected/, writes textured/
// and report.json; bad inputs are named and earlier outputs stay intact.
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <random>

#include <open3d/io/PointCloudIO.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "auv/recon/common/option_set.h"
#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/mesh/mesh_stage.h"
#include "auv/recon/scene/colmap_text.h"
#include "auv/recon/scene/mesh_io.h"
#include "auv/recon/texture/texture_stage.h"
#include "synthetic_scene.h"

namespace fs = std::filesystem;
using namespace auv::recon;
using namespace auv::recon::texture;

namespace {

struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() / ("auv_recon_texture_stage_" + std::to_string(::getpid()) +
                                        "_" + std::to_string(std::random_device{}()));
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
};

/// A survey with mesh/mesh.ply, sparse/ (one PINHOLE camera, four posed images) and the
/// corrected images of the synthetic floor.
void writeSurvey(const Survey& survey, FaceMesh& mesh) {
  mesh = synth::gridMesh(8, 0.8, synth::flat);
  open3d::geometry::TriangleMesh o3d_mesh;
  o3d_mesh.vertices_ = mesh.vertices;
  o3d_mesh.triangles_ = mesh.faces;
  o3d_mesh.ComputeVertexNormals();
  fs::create_directories(survey.mesh());
  scene::writeMeshPly(survey.mesh() / "mesh.ply", o3d_mesh);

  scene::Reconstruction model;
  model.cameras[1] = scene::Camera::pinhole(1, 160, 120, 100, 100, 79.5, 59.5);
  fs::create_directories(survey.corrected() / "left");
  uint32_t id = 1;
  for (const Eigen::Vector3d& c :
       {Eigen::Vector3d(-0.4, -0.3, 1.4), Eigen::Vector3d(0.4, -0.3, 1.4),
        Eigen::Vector3d(-0.4, 0.3, 1.4), Eigen::Vector3d(0.4, 0.3, 1.4)}) {
    const ViewGeometry view =
        synth::lookAt(c, Eigen::Vector3d(c.x() * 0.5, c.y() * 0.5, 0), 160, 120, 100);
    scene::Image image;
    image.id = id;
    image.camera_id = 1;
    image.name = "left/left_0001_00000" + std::to_string(id) + ".png";
    image.setWorldToCamera(view.world_to_camera);
    model.images[id] = image;
    ASSERT_TRUE(
        cv::imwrite((survey.corrected() / image.name).string(), synth::renderTruth(mesh, view)));
    ++id;
  }
  scene::writeColmapText(model, survey.sparse());
}

std::string expectStageError(const Survey& survey, const TextureStageOptions& options) {
  try {
    runTextureStage(survey, options);
  } catch (const StageError& e) {
    EXPECT_EQ(e.stage(), "texture");
    return e.what();
  }
  ADD_FAILURE() << "the texture stage did not fail";
  return {};
}

}  // namespace

TEST(TextureStage, TexturesASurveyAndKeepsEarlierOutputsOnFailure) {
  TempDir dir;
  const Survey survey(dir.path / "survey");
  TextureStageOptions options;
  options.texture.atlas.max_page_size = 1024;

  // Nothing yet: the missing mesh is named with the command that makes it.
  std::string error = expectStageError(survey, options);
  EXPECT_NE(error.find("mesh.ply"), std::string::npos) << error;
  EXPECT_NE(error.find("auv recon mesh"), std::string::npos) << error;

  FaceMesh mesh;
  writeSurvey(survey, mesh);
  const TextureStageResult summary = runTextureStage(survey, options);
  EXPECT_EQ(summary.views, 4u);
  EXPECT_EQ(summary.stats.faces, mesh.faces.size());
  EXPECT_EQ(summary.stats.faces_unseen, 0u);
  const TexturedModel model = readObj(survey.textured() / "model.obj");
  EXPECT_EQ(model.faces.size(), mesh.faces.size());
  EXPECT_TRUE(fs::exists(survey.textured() / "model.mtl"));
  EXPECT_TRUE(fs::exists(survey.textured() / "face_views.csv"));
  const nlohmann::json report = readReport(survey.report());
  EXPECT_EQ(report["stages"]["texture"]["faces_seen"].get<size_t>(), mesh.faces.size());
  // The re-rendered model matches a fresh view of the floor.
  const ViewGeometry check = synth::lookAt(Eigen::Vector3d(0.1, 0, 1.2), Eigen::Vector3d(0, 0, 0));
  const Rendering rendering = renderTexturedModel(model, check);
  EXPECT_GT(psnr(rendering.image, synth::renderTruth(mesh, check), rendering.mask), 30.0);
  const auto obj_size = fs::file_size(survey.textured() / "model.obj");

  // A missing image: named; textured/ untouched.
  const fs::path image = survey.corrected() / "left" / "left_0001_000002.png";
  fs::rename(image, image.string() + ".moved");
  error = expectStageError(survey, options);
  EXPECT_NE(error.find("left_0001_000002.png"), std::string::npos) << error;
  EXPECT_EQ(fs::file_size(survey.textured() / "model.obj"), obj_size);

  // An unreadable image: named.
  std::ofstream(image) << "not a png";
  error = expectStageError(survey, options);
  EXPECT_NE(error.find("left_0001_000002.png"), std::string::npos) << error;
  fs::remove(image);
  fs::rename(image.string() + ".moved", image);

  // A distorted camera: the texturing needs the undistorted model.
  scene::Reconstruction sparse = scene::readColmapText(survey.sparse());
  sparse.cameras[1].model = scene::CameraModel::OPENCV;
  sparse.cameras[1].distortion = {-0.1, 0.01, 0, 0};
  scene::writeColmapText(sparse, survey.sparse());
  error = expectStageError(survey, options);
  EXPECT_NE(error.find("distortion"), std::string::npos) << error;

  // Poses that see nothing of the mesh: "no face", naming the mesh.
  for (auto& [id, img] : sparse.images) {
    img.setWorldToCamera(
        synth::lookAt(Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0, 0, 5)).world_to_camera);
  }
  sparse.cameras[1].model = scene::CameraModel::PINHOLE;
  sparse.cameras[1].distortion.clear();
  scene::writeColmapText(sparse, survey.sparse());
  error = expectStageError(survey, options);
  EXPECT_NE(error.find("no face"), std::string::npos) << error;
  EXPECT_NE(error.find("mesh.ply"), std::string::npos) << error;
  EXPECT_EQ(fs::file_size(survey.textured() / "model.obj"), obj_size);
  EXPECT_EQ(readObj(survey.textured() / "model.obj").faces.size(), mesh.faces.size());
}

// Masks (masks/mask.h): a view whose mask hides everything textures no face; a wrong-size
// mask is named before anything is written.
TEST(TextureStage, MaskedPixelsGiveNoColour) {
  TempDir dir;
  const Survey survey(dir.path / "survey");
  FaceMesh mesh;
  writeSurvey(survey, mesh);
  const std::string hidden = "left_0001_000002.png";
  fs::create_directories(survey.root() / "masks" / "left");
  ASSERT_TRUE(cv::imwrite((survey.root() / "masks" / "left" / (hidden + ".png")).string(),
                          cv::Mat(120, 160, CV_8U, cv::Scalar(0))));
  TextureStageOptions options;
  options.texture.atlas.max_page_size = 1024;
  const TextureStageResult summary = runTextureStage(survey, options);
  EXPECT_EQ(summary.stats.faces_unseen, 0u);  // the other three views see the floor
  std::ifstream csv(survey.textured() / "face_views.csv");
  const std::string text((std::istreambuf_iterator<char>(csv)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text.find(hidden), std::string::npos);
  EXPECT_NE(text.find("left_0001_000001.png"), std::string::npos);
  EXPECT_EQ(readReport(survey.report())["stages"]["texture"]["masked_views"].get<size_t>(), 1u);

  const auto obj_size = fs::file_size(survey.textured() / "model.obj");
  ASSERT_TRUE(cv::imwrite((survey.root() / "masks" / "left.png").string(),
                          cv::Mat(60, 80, CV_8U, cv::Scalar(255))));
  const std::string error = expectStageError(survey, options);
  EXPECT_NE(error.find("masks/left.png"), std::string::npos) << error;
  EXPECT_NE(error.find("80x60"), std::string::npos) << error;
  EXPECT_EQ(fs::file_size(survey.textured() / "model.obj"), obj_size);
}

TEST(TextureStage, ChainsWithTheMeshStageOnASyntheticSurvey) {
  // dense/fused.ply sampled from a gentle terrain -> auv recon mesh (Poisson, trimming) ->
  // auv recon texture from images of the true terrain: the Poisson mesh's orientation and
  // frame work for the texturing, and the model looks like the truth from a new view.
  TempDir dir;
  const Survey survey(dir.path / "survey");
  const synth::Height terrain = [](double x, double y) {
    return 0.08 * std::sin(2 * x) * std::cos(2 * y);
  };
  const FaceMesh truth = synth::gridMesh(40, 1.0, terrain);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  open3d::geometry::PointCloud cloud;
  for (int i = 0; i < 30000; ++i) {
    const double x = u(rng), y = u(rng);
    const Eigen::Vector3d p(x, y, terrain(x, y));
    const double e = 1e-5;
    const Eigen::Vector3d n(-(terrain(x + e, y) - terrain(x - e, y)) / (2 * e),
                            -(terrain(x, y + e) - terrain(x, y - e)) / (2 * e), 1.0);
    cloud.points_.push_back(p);
    cloud.normals_.push_back(n.normalized());
    cloud.colors_.push_back(synth::trueColor(p).cast<double>().reverse() / 255.0);  // RGB
  }
  fs::create_directories(survey.dense());
  ASSERT_TRUE(open3d::io::WritePointCloud((survey.dense() / "fused.ply").string(), cloud));
  mesh::MeshStageOptions mesh_options;
  mesh_options.surface.poisson_depth = 7;
  const mesh::MeshStageResult meshed = mesh::runMeshStage(survey, mesh_options);

  scene::Reconstruction model;
  model.cameras[1] = scene::Camera::pinhole(1, 200, 150, 130, 130, 99.5, 74.5);
  fs::create_directories(survey.corrected() / "right");
  uint32_t id = 1;
  for (const Eigen::Vector3d& c : {Eigen::Vector3d(-0.5, -0.4, 1.3),
                                   Eigen::Vector3d(0.5, -0.4, 1.3), Eigen::Vector3d(-0.5, 0.4, 1.3),
                                   Eigen::Vector3d(0.5, 0.4, 1.3), Eigen::Vector3d(0, 0, 1.6)}) {
    const ViewGeometry view =
        synth::lookAt(c, Eigen::Vector3d(c.x() * 0.6, c.y() * 0.6, 0), 200, 150, 130);
    scene::Image image;
    image.id = id;
    image.camera_id = 1;
    image.name = "right/right_0001_00000" + std::to_string(id) + ".png";
    image.setWorldToCamera(view.world_to_camera);
    model.images[id++] = image;
    ASSERT_TRUE(
        cv::imwrite((survey.corrected() / image.name).string(), synth::renderTruth(truth, view)));
  }
  scene::writeColmapText(model, survey.sparse());
  TextureStageOptions options;
  options.texture.atlas.max_page_size = 2048;
  const TextureStageResult textured = runTextureStage(survey, options);
  std::cout << meshed.stats.triangles << " mesh triangles, " << textured.stats.faces_seen
            << " textured, " << textured.stats.faces_unseen << " unseen" << std::endl;
  EXPECT_EQ(textured.stats.faces, meshed.stats.triangles);
  EXPECT_GT(textured.stats.faces_seen, textured.stats.faces * 9 / 10);

  const TexturedModel result = readObj(survey.textured() / "model.obj");
  const ViewGeometry check =
      synth::lookAt(Eigen::Vector3d(0.15, -0.1, 0.9), Eigen::Vector3d(0.1, 0, 0), 200, 150, 130);
  const Rendering rendering = renderTexturedModel(result, check);
  const double value = psnr(rendering.image, synth::renderTruth(truth, check), rendering.mask);
  std::cout << "held-out view of the Poisson mesh's texture: PSNR " << value << " dB" << std::endl;
  EXPECT_GT(value, 30.0);
}

TEST(TextureStage, OptionsBindToFlagsAndTheConfigSection) {
  TempDir dir;
  const fs::path config = dir.path / "recon.yaml";
  std::ofstream(config) << "texture:\n  smoothness: 0.8\n  local_blending: false\n";
  TextureStageOptions options;
  OptionSet set("texture");
  options.bind(set);
  ASSERT_TRUE(set.parse({"--config", config.string(), "--max-page-size", "2048"}));
  EXPECT_DOUBLE_EQ(options.texture.selection.smoothness, 0.8);
  EXPECT_FALSE(options.texture.atlas.local_blending);
  EXPECT_EQ(options.texture.atlas.max_page_size, 2048);
  EXPECT_THROW(set.parse({"--blend-width", "wide"}), std::invalid_argument);
}
